"""The ``pour`` primitive: tip a held vessel (a tumbler, a beaker: tag ``pourer``) over a container until the loose
pieces in it (beads, :mod:`gendex_envs.pouring`) fall in, then stand it up again.

The vessel has been grasped from its side (the ``side`` grasp family: fingers round it, the palm against it, its mouth
clear) and lifted. A person pours by turning the wrist; the ShadowHand's forearm runs along its fingers and the
UR10e's last wrist joint turns about that line, so :func:`pour` tips the vessel about the fingers' line through the
palm (:func:`pour_axis`), the way that ends with the palm above the vessel. It

1. picks a turn of the held vessel about the vertical (:func:`pour_poses`, the least turn first) for which the arm
   reaches, without collision, the palm pose before tipping and follows the tip by IK every :data:`CHECK_RAD` with
   the arm clear of the table,
2. moves the arm there by a planned motion (the vessel attached to the arm as spheres, the container an obstacle),
3. tips the vessel :data:`TILT_RAD` at :data:`TILT_RAD_PER_STEP` while the palm comes down :data:`RISE_M`
   (:func:`tip_pose`): the lowest point of the vessel's rim ends :data:`LIP_OVER_RIM_M` over the container's rim and
   :data:`LIP_BACK_M` short of its centre (the mouth's opening spans the centre),
4. holds it there :data:`POUR_HOLD_STEPS` while the pieces fall, and turns it back upright.

The vessel is taken as it sits in the hand: a side grasp leans it 20-30 deg, which the tip simply adds to.
Measured rates on unseen seeds: ``benchmarks/results/skills.md``.
"""

from __future__ import annotations

import logging
from collections.abc import Generator, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import sapien

from gendex.solve.collision import box_spheres
from gendex_envs.errors import ExecutionError
from gendex_envs.pouring import POURABLE_TAG

if TYPE_CHECKING:  # pragma: no cover
    from gendex.solve.rigid import RigidPrimitives

log = logging.getLogger(__name__)

TILT_RAD = np.radians(135.0)
"""How far the vessel is tipped: its mouth 45 deg below the horizontal, so pieces roll out over the lip."""
TILT_RAD_PER_STEP = np.radians(3.0)
"""Tipping speed (60 deg/s at 20 Hz): fast enough that the pieces leave as one stream, slow enough that the vessel
does not turn in the hand."""
LIP_OVER_RIM_M = 0.04
"""After tipping, the vessel's lip is this far above the container's rim."""
LIP_BACK_M = 0.02
"""... and this far short of the container's centre along the pour direction (the opening reaches past the lip)."""
RISE_M = 0.06
"""Before tipping, the palm is this much higher than when tipped: it comes down as the vessel turns, so that neither
the upright vessel's bottom (at first) nor its lip (at the end) comes near the container's rim."""
POUR_HOLD_STEPS = 40
"""Steps held tipped while the pieces fall and settle (2 s)."""
UPRIGHT_HOLD_STEPS = 10
YAWS = 16
"""Turns of the held vessel about the vertical that are tried (evenly round, the least first)."""
CHECK_RAD = np.radians(9.0)
"""The tip is checked for IK and collision every this many radians before it is chosen."""
WALL_M = 0.004
"""The lip is this far in from the vessel's outer radius."""


@dataclass(frozen=True)
class Pour:
    """One way to pour: the palm pose before tipping (the tip turns the palm about itself, :func:`tip_pose`), the tip
    as a rotation vector (world), and the turn of the held vessel about the vertical from now."""

    pre: sapien.Pose
    rotvec: np.ndarray
    turn_rad: float


def _pose(env, name: str) -> sapien.Pose:
    pose = env.obj_pose(name)
    return sapien.Pose(pose.p[0].cpu().numpy(), pose.q[0].cpu().numpy())


def _yaw(rad: float) -> sapien.Pose:
    return sapien.Pose(q=[np.cos(rad / 2), 0.0, 0.0, np.sin(rad / 2)])


def vessel_size(env, held: str) -> tuple[float, float]:
    """(height, radius of the lip) of ``held``, scaled."""
    rec = env.asset_record(held)
    scale = env.task_spec.object(held).scale
    lo, hi = np.asarray(rec.bbox_min_m), np.asarray(rec.bbox_max_m)
    return scale * float(hi[2] - lo[2]), scale * float(min(hi[0] - lo[0], hi[1] - lo[1])) / 2 - WALL_M


def pour_axis(palm: sapien.Pose) -> np.ndarray:
    """The horizontal axis the held vessel is tipped about: along the fingers (the palm frame's +z), the way round
    that turns the mouth towards the side the palm faces (its skin, the frame's -y: the vessel's side), which ends
    with the palm above the vessel; ExecutionError if the fingers point down (a grasp from above, over the mouth)."""
    r = palm.to_transformation_matrix()[:3, :3]
    a = np.array([r[0, 2], r[1, 2], 0.0])
    if np.linalg.norm(a) < 0.3:
        raise ExecutionError("the vessel is not held from its side (the fingers point down), so it cannot be tipped "
                             "about them", cause="unsupported")
    a /= np.linalg.norm(a)
    facing = np.array([-r[0, 1], -r[1, 1], 0.0])
    if float(np.cross(a, [0.0, 0.0, 1.0]) @ facing) < 0:  # tipping about +a turns the mouth towards a x up
        a = -a
    return a


def pour_poses(env, held: str, target: str, palm: sapien.Pose, vessel: sapien.Pose) -> list[Pour]:
    """Every way to pour ``held`` into ``target`` from here, the least turn of the held pair about the vertical
    first: for each turn, the palm pose (as it is now, turned) whose roll by :data:`TILT_RAD` about the fingers' line
    through the palm (the wrist's last joint: the ShadowHand's forearm runs along its fingers) ends with the lowest
    point of the vessel's rim :data:`LIP_OVER_RIM_M` over the target's rim and :data:`LIP_BACK_M` short of its
    centre. The vessel is taken as it sits in the hand (a side grasp tilts it 20-30 deg)."""
    in_hand = palm.inv() * vessel
    height, radius = vessel_size(env, held)
    a0 = pour_axis(palm)
    up = np.array([0.0, 0.0, 1.0])
    rim = float(env.obj_pose(target).p[0, 2]) + _top(env, target)
    centre = _pose(env, target).p
    ring = np.linspace(0.0, 2 * np.pi, 36, endpoint=False)
    rim_local = np.column_stack([radius * np.cos(ring), radius * np.sin(ring), np.full(len(ring), height)])
    out = []
    for turn in sorted(np.linspace(-np.pi, np.pi, YAWS, endpoint=False), key=abs):
        a = _yaw(turn).to_transformation_matrix()[:3, :3] @ a0
        d = np.cross(a, up)
        tilt = sapien.Pose(q=np.r_[np.cos(TILT_RAD / 2), np.sin(TILT_RAD / 2) * a])
        palm0 = sapien.Pose(q=(_yaw(turn) * sapien.Pose(q=palm.q)).q)  # turned, at the origin
        tipped = (tilt * palm0 * in_hand).to_transformation_matrix()
        points = rim_local @ tipped[:3, :3].T + tipped[:3, 3]
        lip = points[int(np.argmin(points[:, 2]))]
        goal = np.array([centre[0], centre[1], rim + LIP_OVER_RIM_M]) - LIP_BACK_M * d
        at = goal - lip  # the palm's origin once tipped
        out.append(Pour(sapien.Pose(at + RISE_M * up, palm0.q), a * TILT_RAD, float(abs(turn))))
    return out


def tip_pose(start: sapien.Pose, rotvec: np.ndarray, frac: float, drop_m: float = RISE_M) -> sapien.Pose:
    """The palm ``frac`` of the way through a tip from ``start``: turned by ``frac`` of ``rotvec`` about its own
    origin and ``frac`` of ``drop_m`` lower (negative: higher)."""
    angle = float(np.linalg.norm(rotvec)) * frac
    turn = sapien.Pose(q=np.r_[np.cos(angle / 2), np.sin(angle / 2) * rotvec / float(np.linalg.norm(rotvec))])
    return sapien.Pose(start.p - frac * drop_m * np.array([0.0, 0.0, 1.0]), (turn * sapien.Pose(q=start.q)).q)


def held_spheres(env, held: str) -> tuple[np.ndarray, np.ndarray]:
    """Spheres covering ``held``'s own box where it is now, however it is turned (world centres, radii): the box of
    a vessel tilted in the hand, taken in the world's axes, is half as wide again."""
    rec = env.asset_record(held)
    scale = env.task_spec.object(held).scale
    centres, radii = box_spheres(np.asarray(rec.bbox_min_m) * scale, np.asarray(rec.bbox_max_m) * scale)
    m = _pose(env, held).to_transformation_matrix()
    return centres @ m[:3, :3].T + m[:3, 3], radii


def _top(env, target: str) -> float:
    """Height of ``target``'s rim above its origin (scaled)."""
    rec = env.asset_record(target)
    return env.task_spec.object(target).scale * float(rec.bbox_max_m[2])


class _Pourer:
    """The moves of one pour."""

    def __init__(self, rigid: RigidPrimitives, target: str):
        self.rigid, self.env, self.m, self.target, self.held = rigid, rigid.env, rigid.m, target, rigid.held
        self.step_rad = rigid.config.carry_step_rad
        self.cover = (*held_spheres(self.env, self.held), self.m.target())
        """The held vessel as spheres fixed to the palm: obstacles of the planned move to the pose before tipping."""

    def attach(self) -> None:
        self.m.collision.attach(*self.cover)

    def palm(self) -> sapien.Pose:
        return self.m.ik.fk(self.m.qpos())

    def tips(self, p: Pour, q: np.ndarray) -> bool:
        """Whether the arm follows the tip of ``p`` from ``q`` (at ``p.pre``): IK every :data:`CHECK_RAD`, the arm
        free of collision. The vessel itself is left out: its lowest point while tipping is its lip, which ends
        :data:`LIP_OVER_RIM_M` over the rim (its spheres, a box's cover, reach a centimetre past it)."""
        n = max(1, int(np.ceil(TILT_RAD / CHECK_RAD)))
        self.m.collision.detach()
        try:
            for k in range(1, n + 1):
                q = self.m.ik.solve(tip_pose(p.pre, p.rotvec, k / n), q, restarts=0)
                if q is None or not self.m.collision.is_free(q):
                    log.debug("the tip stops at %d/%d: %s", k, n, "no IK" if q is None else
                              f"collision ({self.m.collision.clearance(q):.3f} m)")
                    return False
            return True
        finally:
            self.attach()

    def tip(self, rotvec: np.ndarray, drop_m: float) -> Generator[np.ndarray, None, float]:
        """Turn the palm by ``rotvec`` about itself while it comes down ``drop_m`` (:func:`tip_pose`; turning back:
        the opposite rotation and a negative drop), IK per step at :data:`TILT_RAD_PER_STEP`; the fraction done."""
        m = self.m
        start = m.ik.fk(m.target())
        n = max(1, int(np.ceil(float(np.linalg.norm(rotvec)) / TILT_RAD_PER_STEP)))
        q = m.target()
        for k in range(1, n + 1):
            nq = m.ik.solve(tip_pose(start, rotvec, k / n, drop_m), q, restarts=0)
            if nq is None:
                log.info("tipping stopped at step %d/%d: the arm reaches no further", k - 1, n)
                return (k - 1) / n
            q = nq
            t = m.target()
            t[m.arm] = q[m.arm]
            yield m.emit(t)
        return 1.0

    def choose(self) -> tuple[Pour, Iterator[np.ndarray]]:
        """The first way to pour (in :func:`pour_poses`' order) whose pose before tipping the arm reaches without
        collision, whose tip it follows and that a planned path reaches: that way and the path."""
        m = self.m
        q_now = m.target()
        tried = pour_poses(self.env, self.held, self.target, self.palm(), _pose(self.env, self.held))
        reached = 0
        for p in tried:
            q_pre = m.ik.solve(p.pre, q_now, restarts=20, valid=m.collision.is_free)
            if q_pre is None or not self.tips(p, q_pre):
                log.debug("turn %.2f rad: %s", p.turn_rad, "no collision-free arm configuration" if q_pre is None
                          else "the arm does not follow the tip")
                continue
            reached += 1
            try:
                return p, m.plan_arm(q_pre, max_step_rad=self.step_rad)
            except ExecutionError as err:
                log.debug("turn %.2f rad: %s", p.turn_rad, err)
        raise ExecutionError(f"no reachable way to pour from {self.held!r} into {self.target!r} ({len(tried)} tried, "
                             f"{reached} reached but not by a planned path)", cause="no_plan" if reached else "no_ik")


def pour(rigid: RigidPrimitives, target: str) -> Iterator[np.ndarray]:
    """Pour what the held vessel holds into ``target`` (module docstring)."""
    m, held, env = rigid.m, rigid.held, rigid.env
    if held is None:
        raise ExecutionError(f"pouring into {target!r} needs a vessel in the hand; it holds nothing", cause="slipped")
    pieces = tuple(n for n in env.objects if POURABLE_TAG in env.asset_record(n).tags)
    p = _Pourer(rigid, target)
    m.collision.set_obstacles(m.object_boxes(exclude=(held, *pieces)))
    p.attach()
    try:
        way, path = p.choose()
        log.info("pouring from %r into %r (the vessel turned %.1f rad about the vertical)", held, target, way.turn_rad)
        yield from path
    finally:
        m.collision.detach()
    yield from m.settle()
    done = yield from p.tip(way.rotvec, RISE_M)
    if done < 0.5:
        raise ExecutionError(f"the arm tipped {held!r} only {done:.0%} of the way over {target!r}", cause="no_ik")
    yield from m.hold(POUR_HOLD_STEPS)
    yield from p.tip(-way.rotvec * done, -RISE_M * done)
    yield from m.hold(UPRIGHT_HOLD_STEPS)


__all__ = ["Pour", "held_spheres", "pour", "pour_axis", "pour_poses", "tip_pose", "vessel_size"]
