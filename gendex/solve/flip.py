"""The ``flip`` primitive: turn a held object upside down and lower it onto the table where it was.

The object has been grasped from its side (the ``side`` grasp family: a tall object, fingers horizontal round it, the
palm against it) and lifted. The UR10e's last wrist joint turns about the ShadowHand's fingers' line (the forearm
runs along it), so half a turn about that line turns the object over while the forearm stays where it was. A side
grasp holds a tall object leaning 20-30 deg; squaring that lean once it is upside down would swing the forearm down
into the table (measured: the UR10e's wrist on the table with the object's top still 25 cm up), so the object keeps
its lean and is let go low instead. :func:`flip`

1. raises the object's centre to :data:`TURN_HEIGHT_M`, where the turn keeps it clear of the table,
2. turns the palm half a turn about the fingers' line through the object's centre (:meth:`ArmHandMotion.turn_about`:
   the object stays where it is, the palm goes round it), at :data:`TURN_RAD_PER_STEP`,
3. lowers it straight down until its lowest point is :data:`DROP_M` over the table or the next
   :data:`LOWER_STEP_M` would bring the arm (the planner's collision model) within its margin of the table or of
   another object.

A release stage lets go afterwards: from 3-4 cm the object drops onto its top and stays there, leaning 22-29 deg as
the grasp held it (a tumbler or a paper cup; a beaker lands on its side about half the time, a narrow box or a bottle
on its cap topples). Measured rates on unseen seeds: ``benchmarks/results/skills.md``.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from typing import TYPE_CHECKING

import numpy as np
import sapien

from gendex.solve.pour import pour_axis
from gendex_envs.errors import ExecutionError
from gendex_envs.geometry import tilt

if TYPE_CHECKING:  # pragma: no cover
    from gendex.solve.rigid import RigidPrimitives

log = logging.getLogger(__name__)

TURN_RAD_PER_STEP = np.radians(3.0)
"""Turning speed (60 deg/s at 20 Hz), as a pour tips its vessel: slow enough that the object does not turn in the
hand."""
TURN_HEIGHT_M = 0.32
"""The object's centre is raised this high over the table before it turns (a 14 cm glass clears it with room; the
arm's collision model then tells how far it may come down)."""
LOWER_STEP_M = 0.01
DROP_M = 0.01
"""Lowered until its lowest point (its top, now) is this far over the table, or the arm is as low as it may go."""
MIN_TURN = 0.75
"""A turn the arm stops short of this share of is a failure (the object would land on its side)."""


def flip(rigid: RigidPrimitives, name: str) -> Iterator[np.ndarray]:
    """Turn the held ``name`` upside down and lower it to the table at its own xy (module docstring)."""
    m, env, held = rigid.m, rigid.env, rigid.held
    if held != name:
        raise ExecutionError(f"flipping {name!r} needs it in the hand; it holds {held!r}", cause="slipped")
    lo, hi = m.world_aabb(name)
    rise = env.table_height + TURN_HEIGHT_M - float(lo[2] + hi[2]) / 2
    if rise > 0:
        yield from m.cartesian(np.array([0.0, 0.0, rise]), rigid.config.motion.lift_m_per_step, guard=True,
                               paced=True, partial=True)
    lo, hi = m.world_aabb(name)
    done = yield from m.turn_about((lo + hi) / 2, pour_axis(m.ik.fk(m.target())) * np.pi, TURN_RAD_PER_STEP,
                                   guard=True)
    if done < MIN_TURN:
        raise ExecutionError(f"the arm turned {name!r} only {done:.0%} of half a turn", cause="no_ik")
    yield from m.hold(rigid.config.motion.settle_steps)
    lean = 180.0 - float(np.degrees(tilt(env.obj_pose(name).q, env.init_obj_quat(name))[0]))
    m.collision.set_obstacles(m.object_boxes(exclude=(name,)))
    q = m.target()
    while (step := min(LOWER_STEP_M, float(m.world_aabb(name)[0][2]) - env.table_height - DROP_M)) > 1e-4:
        palm = m.ik.fk(q)
        nq = m.ik.solve(sapien.Pose(palm.p - [0.0, 0.0, step], palm.q), q, restarts=0)
        if nq is None or not m.collision.is_free(nq):
            break
        yield from m.cartesian(np.array([0.0, 0.0, -step]), rigid.config.motion.lift_m_per_step, guard=True)
        q = m.target()
    log.info("turned %r over (%.0f%% of half a turn, %.0f deg off upside down); its lowest point %.3f m over the "
             "table", name, 100 * done, lean, float(m.world_aabb(name)[0][2]) - env.table_height)
    yield from m.hold(rigid.config.motion.settle_steps)


__all__ = ["flip"]
