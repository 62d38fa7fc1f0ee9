"""The push primitive: slide a rigid object across the table with the flat hand, closed loop on its measured pose,
without grasping it (:meth:`gendex.solve.rigid.RigidPrimitives.push` runs it)."""

from __future__ import annotations

import logging
from collections.abc import Iterator
from typing import TYPE_CHECKING

import numpy as np

from gendex.solve.grasp import PALM_THICKNESS_M, GraspPlan, GraspSynthesizer, palm_rotation, pose_of
from gendex.solve.hand import TIP_ALONG_M
from gendex_envs.errors import ExecutionError

if TYPE_CHECKING:  # pragma: no cover
    from gendex.solve.rigid import RigidPrimitives

log = logging.getLogger(__name__)

PUSH_HAND = {"THJ4": 0.0, "THJ3": 0.0, "THJ2": 0.0, "THJ1": 0.0, "THJ0": 0.0} | {
    f + j: 0.0 for f in ("FF", "MF", "RF", "LF") for j in ("J3", "J2", "J1", "J0")}
"""A flat hand: fingers straight and together, thumb along the palm."""
PUSH_ALONG_M = 0.07
"""The object meets the pushing palm this far along it from the palm origin (towards the fingers)."""
PUSH_GAP_M = 0.005
PUSH_TIP_CLEARANCE_M = 0.012
"""Fingertips-down pushing: the tips' ends this far above the table."""
PUSH_APPROACH_M = 0.05
PUSH_MIN_HEIGHT_M = 0.03
PUSH_MAX_HEIGHT_M = 0.09
"""Palm origin heights above the table tried, lowest first."""
PUSH_M_PER_STEP = 0.008
PUSH_INTO_M = 0.015
PUSH_LEAD_M = 0.012
"""How far the palm's target may run into the object's back face (the PD lag turns it into the pushing force), and
how far short of the goal (along the first push direction) pushing stops."""
PUSH_MAX_STEPS = 150
PUSH_STOP_FRACTION = 0.5
"""Pushing stops once the object's centre is within this fraction of the task's tolerance of the goal."""

def push(rigid: RigidPrimitives, name: str, goal_xy: np.ndarray, tolerance_m: float) -> Iterator[np.ndarray]:
    """Slide ``name`` across the table until its centre is within ``tolerance_m`` of ``goal_xy``, without
    grasping it: the flat hand (fingers straight and together, thumb along the palm; fingers down like a broom, or
    sideways) is brought behind the object by the staged approach; then, every step, the palm turns to face the
    goal from the object's *measured* centre and advances :data:`PUSH_M_PER_STEP` while it is no more than
    :data:`PUSH_INTO_M` into the object's back face."""
    m = rigid.m
    plan, q_pre, lateral, synth = _push_plan(rigid, name, goal_xy)
    rigid.plan = plan
    yield from rigid.bring_hand(name, plan, q_pre, synth)
    cmd = m.ik.fk(m.target()).p  # the commanded palm position (kept here: IK residuals must not accumulate)
    height = float(cmd[2])
    for _ in range(PUSH_MAX_STEPS):
        shape = rigid.shape(name)
        center = shape.footprint().center
        rest = goal_xy - center
        if float(np.linalg.norm(rest)) <= PUSH_STOP_FRACTION * tolerance_m or float(rest @ plan.approach[:2]) < \
                PUSH_LEAD_M:
            break  # there, or about to pass it (the palm's lag and the object's slide carry it the rest)
        d = np.append(rest / np.linalg.norm(rest), 0.0)
        side = np.array([-d[1], d[0], 0.0])
        lo, _ = shape.extent_along(d)
        behind = float(center @ d[:2] - lo) + PALM_THICKNESS_M  # palm origin to the object's centre, along d
        rel = np.append(center, height) - (cmd - lateral)  # object centre seen from the palm's push point
        ahead = float(rel @ d) - behind  # > 0: the palm is short of the object's back face
        # forward while the palm is at most PUSH_INTO_M into the back face; steering is by re-aiming alone (the
        # palm turns to face the goal from where the object is): a sideways palm correction only dragged the
        # object along by friction (measured: 11/12 with one at 30 % gain, 12/12 without)
        step = min(PUSH_M_PER_STEP, max(0.0, ahead + PUSH_INTO_M)) * d
        fingers = plan.palm.to_transformation_matrix()[:3, 2]
        if abs(fingers[2]) < 0.5:  # fingers sideways: they turn with the push direction
            fingers = np.sign(fingers @ np.array([-plan.approach[1], plan.approach[0], 0.0])) * side
        cmd = cmd + step
        turned = pose_of(palm_rotation(fingers, d), cmd)  # the palm keeps facing the push direction
        q = m.ik.solve(turned, m.target(), restarts=0)
        if q is None:
            raise ExecutionError(f"no IK for the palm pushing {name!r} at {np.round(cmd, 3)}", cause="no_ik")
        t = m.target()
        t[m.arm] = q[m.arm]
        yield m.emit(t)
    else:
        left = float(np.linalg.norm(goal_xy - rigid.shape(name).footprint().center))
        raise ExecutionError(f"{name!r} still {left:.3f} m from where it is pushed to after {PUSH_MAX_STEPS} "
                             "steps", cause="target_not_reached")
    rigid.plan = None
    yield from m.cartesian(np.array([0.0, 0.0, 0.05]) - 0.04 * plan.approach, 0.01)

def _push_plan(rigid: RigidPrimitives, name: str, goal_xy: np.ndarray
               ) -> tuple[GraspPlan, np.ndarray, np.ndarray, GraspSynthesizer]:
    """The first flat-hand pose behind ``name`` whose approach along the push line keeps the hand off everything
    and whose pre-push pose the arm reaches without collision; the arm's joint vector there; the palm's horizontal
    offset from the push line; and the synthesizer that checked the hand's path. Poses tried: fingers pointing down
    (tips just above the table, the fingers a broom behind the object), then fingers to either side at rising
    heights."""
    env, m = rigid.env, rigid.m
    shape = rigid.shape(name)
    fp = shape.footprint()
    rest = goal_xy - fp.center
    if float(np.linalg.norm(rest)) < 1e-6:
        raise ExecutionError(f"{name!r} is already where it is pushed to", cause="unsupported")
    d = np.append(rest / np.linalg.norm(rest), 0.0)
    lo, _ = shape.extent_along(d)
    behind = float(fp.center @ d[:2] - lo) + PALM_THICKNESS_M + PUSH_GAP_M
    line = np.append(fp.center, env.table_height) - behind * d
    others = tuple(rigid.shape(o) for o in env.objects if o != name and o not in env.articulations)
    synth = GraspSynthesizer(rigid.hand, shape, env.table_height, 0.0, others)
    m.avoid_objects(exclude=(name,))
    tips = float(np.max(rigid.hand.pads(PUSH_HAND, TIP_ALONG_M)[:, 2]))
    down = np.array([0.0, 0.0, -1.0])
    poses = [(down, np.zeros(3), tips + PUSH_TIP_CLEARANCE_M, "fingers down")]
    for h in np.arange(PUSH_MIN_HEIGHT_M, PUSH_MAX_HEIGHT_M + 1e-9, 0.01):
        for side in (1.0, -1.0):
            f = side * np.array([-d[1], d[0], 0.0])
            poses.append((f, -PUSH_ALONG_M * f, h, f"fingers sideways, palm {100 * h:.0f} cm up"))
    for f, lateral, h, note in poses:
        p = line + lateral + np.array([0.0, 0.0, h])
        plan = GraspPlan("push", pose_of(palm_rotation(f, d), p), approach=d, approach_m=PUSH_APPROACH_M,
                         open_hand=dict(PUSH_HAND), closing=(), note=note)
        if not synth.path_clear(PUSH_HAND, plan.palm, -PUSH_APPROACH_M * d, np.zeros(3)):
            continue
        q_pre = m.ik.solve(plan.pregrasp, m.with_hand(m.target(), plan.open_hand), restarts=20,
                           valid=m.collision.is_free)
        if q_pre is not None:
            log.info("pushing %r with %s", name, note)
            return plan, q_pre, lateral, synth
        log.debug("push pose %s: no collision-free IK", note)
    raise ExecutionError(f"no flat-hand pose behind {name!r} that clears the table and the objects and that the "
                         "arm reaches", cause="no_ik")
