"""The ``hang`` primitive: thread a held mug's handle onto a peg of a stand (an asset tagged ``hang_on``,
:mod:`gendex_envs.assets.procedural_hanging`) and lower it until the peg bears it.

The mug has been grasped by its body and lifted. A peg leaves its post rising a little towards its tip; the handle's
opening (the mug's ``handle_hole`` anchor, about 19 x 35 mm round an 8 mm peg) has to come onto it along its axis.
So :func:`hang`

1. picks the way to thread it the arm reaches (:func:`thread_poses`: for each peg and each of the two ways round the
   mug can face along it, the palm poses that put the opening :data:`PRE_M` beyond the tip, then on the peg with the
   mug's side :data:`ROOT_GAP_M` off the post, the mug upright), those keeping the palm off the post's side first,
   then the least turn of the wrist,
2. moves the arm there by a planned motion (the mug attached to the arm as spheres, each convex piece of the stand
   an obstacle box),
3. aims again where the mug turned in the hand on the way (by more than :data:`REAIM_RAD`), then centres the opening
   on the peg's axis from where the mug really is in the hand (it sags in a pinch),
4. slides it along the axis onto the peg, centres it again, and
5. lowers it until the mug stops following the palm: the peg bears it. The release stage lets go; the executor's
   final hold waits for the mug to stop swinging (:data:`gendex.solve.executor.SWING_WAIT_STEPS`).

Measured while developing (seeds 0-8 and 20-27, stands +-3 cm and 30 deg, the mug +-8 cm and 90 deg): see
``benchmarks/results/skills.md`` for rates on unseen seeds.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Generator, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import sapien

from gendex.solve.collision import Box, box_spheres
from gendex_envs.errors import ExecutionError

if TYPE_CHECKING:  # pragma: no cover
    from gendex.solve.rigid import RigidPrimitives

log = logging.getLogger(__name__)

PRE_M = 0.14
"""Before threading, the opening is this far beyond the peg's tip along its axis."""
ROOT_GAP_M = 0.012
"""On the peg, the mug's side is this far from the peg's root (the post or rail): the opening goes that much further
out than the mug is wide along the peg."""
TIP_KEEP_M = 0.015
"""... but at least this far in from the peg's tip."""
THREAD_M_PER_STEP = 0.004
"""Palm speed along the peg (8 cm/s at 20 Hz)."""
LOWER_M = 0.03
"""How far the palm is lowered at most once the peg is through (the opening is 35 mm tall)."""
LOWER_M_PER_STEP = 0.002
RESTING_M = 0.004
"""The mug rests on the peg once the palm has gone this much further down than it."""
CENTRE_TOLERANCE_M = 0.003
"""The opening's middle is centred on the peg's axis (before threading) within this; the opening leaves 5 mm a side
round the peg."""
CENTRE_TRIES = 4
"""Moves at most to centre the opening, each from where it was measured."""
REAIM_RAD = 0.07
"""The mug is turned back upright, its opening along the peg, when off by more than this (4 deg: the opening leaves
5 mm a side round the peg over its 12 mm length)."""
REAIM_TRIES = 3
"""Re-aims at most after the planned move to the stand."""
REARM_TRIES = 5
"""IK restarts at most for another arm configuration where the line onto the peg cannot start."""
ALONG_STEP_M = 0.008
ALONG_MORE_M = 0.02
"""A way to thread the mug is taken only where IK follows the palm's straight line onto the peg, and this much
further (where the opening was centred), every ``ALONG_STEP_M`` (an arm at the end of its reach stopped half way, 1
of 8)."""
HAND_SIDE_M = 0.01
"""A way round that puts the palm more than this nearer the post than the opening is tried last."""
SETTLE_STEPS = 6
"""Steps held still before the opening is measured (the mug swings a little in a pinch after a move)."""


@dataclass(frozen=True)
class Thread:
    """One way to hang the mug on one peg: the palm poses with the opening before the tip (``pre``) and on the peg
    (``on``), the peg's axis, and the opening's world points there."""

    peg: int
    pre: sapien.Pose
    on: sapien.Pose
    axis: np.ndarray
    hole_pre: np.ndarray
    hole_on: np.ndarray
    turn_rad: float


def _anchor(params: dict, name: str) -> np.ndarray:
    return np.array([params[f"{name}_{a}"] for a in "xyz"], dtype=np.float64)


def pegs_world(env, stand: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """(root, tip) of each peg of ``stand`` in the world (env 0)."""
    rec, pose = env.asset_record(stand), env.obj_pose(stand)
    scale = env.task_spec.object(stand).scale
    h = sapien.Pose(pose.p[0].cpu().numpy(), pose.q[0].cpu().numpy())
    params = rec.entry.params
    return [tuple((h * sapien.Pose(scale * _anchor(params, f"peg{k}_{end}"))).p for end in ("root", "tip"))
            for k in range(int(params.get("pegs", 0)))]


def hole_local(env, held: str) -> np.ndarray:
    """The middle of ``held``'s handle opening in its own frame (scaled)."""
    params = env.asset_record(held).entry.params
    if "handle_hole_x" not in params:
        raise ExecutionError(f"{held!r} has no handle to hang it by (its asset records no handle_hole)",
                             cause="unsupported")
    scale = env.task_spec.object(held).scale
    return scale * _anchor(params, "handle_hole")


def thread_poses(env, held: str, stand: str, palm: sapien.Pose, mug: sapien.Pose) -> list[Thread]:
    """Every way to hang ``held`` on a peg of ``stand``: those that keep the palm off the post's side of the opening
    first (:data:`HAND_SIDE_M`), then the least turn of the held mug about the vertical. ``palm`` and ``mug`` are
    their world poses now (the mug's pose in the hand stays as it is)."""
    in_hand = palm.inv() * mug
    hole = hole_local(env, held)
    rec = env.asset_record(held)
    scale = env.task_spec.object(held).scale
    half_y = scale * max(-rec.bbox_min_m[1], rec.bbox_max_m[1])  # the mug's half width along the peg
    x_now = mug.to_transformation_matrix()[:3, 0]
    yaw_now = float(np.arctan2(x_now[1], x_now[0]))
    out = []
    for k, (root, tip) in enumerate(pegs_world(env, stand)):
        axis = (tip - root) / np.linalg.norm(tip - root)
        flat = axis[:2] / np.linalg.norm(axis[:2])
        for yaw in (np.arctan2(-flat[0], flat[1]), np.arctan2(flat[0], -flat[1])):  # the mug's y along the peg
            q = np.array([np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)])
            rot = sapien.Pose(q=q).to_transformation_matrix()[:3, :3]
            poses, holes = [], []
            length = float(np.linalg.norm(tip - root))
            for s in (length + PRE_M, min(half_y + ROOT_GAP_M, length - TIP_KEEP_M)):
                point = root + s * axis
                goal_mug = sapien.Pose(point - rot @ hole, q)
                poses.append(goal_mug * in_hand.inv())
                holes.append(point)
            turn = float(abs((yaw - yaw_now + np.pi) % (2 * np.pi) - np.pi))
            out.append(Thread(k, poses[0], poses[1], axis, holes[0], holes[1], turn))
    # the hand on the post's side of the opening meets the post (or the rail) before the mug is on: the other way
    # round first
    return sorted(out, key=lambda t: (float((t.on.p - t.hole_on) @ t.axis) < -HAND_SIDE_M, t.turn_rad))


class _Hanger:
    """The moves of one hang."""

    def __init__(self, rigid: RigidPrimitives, stand: str):
        self.rigid, self.env, self.m, self.stand, self.held = rigid, rigid.env, rigid.m, stand, rigid.held
        self.step_rad = rigid.config.carry_step_rad  # as slow as a carry: a mug pinched by its rim turns in the hand

    def palm(self) -> sapien.Pose:
        return self.m.ik.fk(self.m.qpos())

    def mug(self) -> sapien.Pose:
        pose = self.env.obj_pose(self.held)
        return sapien.Pose(pose.p[0].cpu().numpy(), pose.q[0].cpu().numpy())

    def hole(self) -> np.ndarray:
        """Where the handle's opening is now (world)."""
        return (self.mug() * sapien.Pose(hole_local(self.env, self.held))).p

    def choose(self) -> tuple[Thread, Iterator[np.ndarray]]:
        """The first way to thread the mug (in :func:`thread_poses`' order) whose first palm pose the arm reaches
        without collision, whose straight line onto the peg it follows (:meth:`along`) and that a planned path
        reaches from here: that way and the path."""
        m = self.m
        q_now = m.target()
        tried = thread_poses(self.env, self.held, self.stand, self.palm(), self.mug())
        reached = 0
        for t in tried:
            q_pre = m.ik.solve(t.pre, q_now, restarts=20, valid=m.collision.is_free)
            if q_pre is None or not self.along(t, q_pre):
                log.debug("peg %d, the mug turned %.1f rad: %s", t.peg, t.turn_rad,
                          "no collision-free arm configuration" if q_pre is None else "no reach onto the peg")
                continue
            reached += 1
            try:
                return t, m.plan_arm(q_pre, max_step_rad=self.step_rad)
            except ExecutionError as err:
                log.debug("peg %d, the mug turned %.1f rad: %s", t.peg, t.turn_rad, err)
        raise ExecutionError(f"no reachable way to thread the {self.held!r}'s handle onto a peg of {self.stand!r} "
                             f"({len(tried)} tried, {reached} reached but not by a planned path)",
                             cause="no_plan" if reached else "no_ik")

    def along(self, t: Thread, q: np.ndarray) -> bool:
        """Whether the arm follows the palm from ``t.pre`` (at ``q``) straight to ``t.on`` and :data:`ALONG_MORE_M`
        on, as the threading will (IK every :data:`ALONG_STEP_M`, each from the last)."""
        d = t.on.p - t.pre.p
        d = d * (1.0 + ALONG_MORE_M / float(np.linalg.norm(d)))
        n = int(np.ceil(np.linalg.norm(d) / ALONG_STEP_M))
        for k in range(1, n + 1):
            pose = sapien.Pose(t.pre.p + d * k / n, t.pre.q)
            q = self.m.ik.solve(pose, q, restarts=0)
            if q is None:
                return False
        return True

    def rearm(self, t: Thread) -> Generator[np.ndarray, None, bool]:
        """Where the arm cannot start the straight line onto the peg (centring moved it to the end of a joint's
        range), move it, planned, to another configuration holding the palm where it is that follows the line; False
        if there is none."""
        m = self.m
        palm = m.ik.fk(m.target())
        here = dataclasses.replace(t, pre=palm, on=sapien.Pose(palm.p + (t.on.p - t.pre.p), palm.q))
        for _ in range(REARM_TRIES):
            q = m.ik.solve(palm, m.target(), restarts=20, valid=m.collision.is_free)
            if q is None or not self.along(here, q):
                continue
            try:
                path = m.plan_arm(q, max_step_rad=self.step_rad)
            except ExecutionError:
                continue
            log.info("the arm could not start onto the peg: another arm configuration")
            yield from path
            return True
        return False

    def misaligned(self, t: Thread) -> float:
        """How far (rad) the mug is from upright with its opening's axis along the peg: the larger of its tilt and
        its turn about the vertical."""
        r = self.mug().to_transformation_matrix()[:3, :3]
        flat = t.axis[:2] / np.linalg.norm(t.axis[:2])
        y = r[:2, 1] / max(float(np.linalg.norm(r[:2, 1])), 1e-9)
        return max(float(np.arccos(np.clip(r[2, 2], -1.0, 1.0))), float(np.arccos(np.clip(abs(y @ flat), 0.0, 1.0))))

    def centre(self, t: Thread, point: np.ndarray) -> Iterator[np.ndarray]:
        """Move the palm until the opening's middle is within :data:`CENTRE_TOLERANCE_M` of ``point``."""
        for _ in range(CENTRE_TRIES):
            yield from self.m.hold(SETTLE_STEPS)
            error = point - self.hole()
            log.debug("handle opening %.1f mm off", 1000 * float(np.linalg.norm(error)))
            if float(np.linalg.norm(error)) < CENTRE_TOLERANCE_M:
                return
            yield from self.m.cartesian(error, THREAD_M_PER_STEP / 2, guard=True, partial=True)

    def lower(self) -> Iterator[np.ndarray]:
        """Lower the palm until the mug stops following it (the peg bears it)."""
        m = self.m
        palm0, z0 = self.palm().p[2], self.mug().p[2]
        n = int(np.ceil(LOWER_M / LOWER_M_PER_STEP))
        for k, action in enumerate(m.cartesian(np.array([0.0, 0.0, -LOWER_M]), LOWER_M_PER_STEP, guard=True)):
            yield action
            if k < n - 1 and (palm0 - self.palm().p[2]) - (z0 - self.mug().p[2]) > RESTING_M:
                return
        yield from m.hold(SETTLE_STEPS)


def hang(rigid: RigidPrimitives, stand: str) -> Iterator[np.ndarray]:
    """Hang the held mug on a peg of ``stand`` (module docstring)."""
    m, held = rigid.m, rigid.held
    if held is None:
        raise ExecutionError(f"hanging something on {stand!r} needs it in the hand; it holds nothing", cause="slipped")
    h = _Hanger(rigid, stand)
    # the stand as a box per convex piece (its bounding box holds the pegs' whole reach), every other object as one
    m.collision.set_obstacles(m.object_boxes(exclude=(held, stand))
                              + [Box(p.vertices.min(axis=0) - 0.01, p.vertices.max(axis=0) + 0.01, stand)
                                 for p in rigid.shape(stand).parts])
    lo, hi = m.world_aabb(held)
    m.collision.attach(*box_spheres(lo, hi), m.target())
    try:
        t, path = h.choose()
        log.info("hanging %r on peg %d of %r (the mug turned %.1f rad)", held, t.peg, stand, t.turn_rad)
        yield from path
    finally:
        m.collision.detach()
    for _ in range(REAIM_TRIES):  # a mug pinched by its rim turns in the hand on the way (20-30 deg, 1 of 8)
        yield from m.hold(SETTLE_STEPS)
        off = h.misaligned(t)
        if off <= REAIM_RAD:
            break
        log.info("the %r turned %.0f deg in the hand: aiming again", held, np.degrees(off))
        try:  # the ways to thread it from how it is held now (the same way round needs no turn now: first)
            t, path = h.choose()
        except ExecutionError:
            break
        yield from path
    yield from h.centre(t, t.hole_pre)
    done = yield from m.cartesian(t.hole_on - t.hole_pre, THREAD_M_PER_STEP, guard=True, partial=True)
    if done == 0.0 and (yield from h.rearm(t)):  # stuck before the tip: the same palm pose, another arm configuration
        done = yield from m.cartesian(t.hole_on - t.hole_pre, THREAD_M_PER_STEP, guard=True, partial=True)
    if done < 1.0:
        raise ExecutionError(f"the arm reaches no further threading the {held!r} onto {stand!r} ({done:.0%} of the "
                             "way)", cause="no_ik")
    yield from h.centre(t, t.hole_on)
    yield from h.lower()


__all__ = ["Thread", "hang", "hole_local", "pegs_world", "thread_poses"]
