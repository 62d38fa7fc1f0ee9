"""Scripted primitives for articulated targets: open a hinged door (or lid) by hooking its handle bar and pulling.

Three primitives, run by :class:`~gendex.solve.executor.StageExecutor` for stages whose target is an
articulated object (skills ``reach``, ``grasp`` and ``open``):

- ``approach_handle`` — reads the main joint of the target from the live articulation (hinge point and axis from
  the joint's world frame, joint position, the handle link's pose; the object's pose is randomized, so nothing is
  taken from the nominal layout) and synthesizes *hook grasps* of the handle bar: palm parallel to the door's
  front, facing it :data:`PALM_STANDOFF_M` from the bar's axis, fingers straight and crossing the bar, which lies
  :data:`BAR_ALONG_M` along the fingers from the palm origin (under the proximal phalanges). Candidates differ by
  the finger direction (towards the hinge first: then the forearm stays beyond the door's free edge for the whole
  swing). A candidate is kept only if the arm reaches the pre-pose (:data:`PRE_M` out from the door) without
  collision *and* can follow the handle along the whole arc to the opening goal (IK chained along sampled door
  angles, collision-checked against the cabinet body). The arm is planned to the pre-pose and moves straight in.
- ``hook`` — guarded closing of the four fingers (each control step at most ``GUARD_RAD`` beyond the measured
  angles): the proximal phalanges stop on the bar and the middle and distal phalanges curl behind it, into the gap
  between bar and door.
- ``pull`` — closed loop: every control step it re-reads the door angle ``q``, places the palm where the grasp
  (fixed in the handle link's frame) will be at ``q + lead`` on the arc about the hinge axis, position *and*
  orientation (the palm yaws with the door), and solves IK from the current arm target. It stops once the door
  is :data:`GOAL_MARGIN` past the success fraction of its opening. If the door stalls (the hook slipped), the
  attempt ends with ``ExecutionError``.

Geometric conventions used (those of :mod:`gendex_envs.assets.articulated`, the catalog's articulated assets): a
door's front faces -x of its link frame, and its handle is a bar parallel to the hinge axis, ``handle_point_m``
(the grip centre) on the bar's axis. :class:`JointFrame` is the arc computation: where a point fixed to the moving
link is at any joint position.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, TypeVar

import numpy as np
import sapien

from gendex.solve.collision import Box, rotated_box_cover
from gendex.solve.grasp import axis_rotation, palm_rotation
from gendex.solve.shape import ObjectShape, PosedShape
from gendex_envs.errors import ExecutionError
from gendex_envs.physx import px_objects

if TYPE_CHECKING:  # pragma: no cover
    from gendex.solve.motion import ArmHandMotion
    from gendex_envs.task_env import TaskEnv

log = logging.getLogger(__name__)
T = TypeVar("T")

DOOR_FRONT_LOCAL = np.array([-1.0, 0.0, 0.0])
"""Outward normal of a door's front in its link frame (catalog convention: fronts face -x)."""
PALM_STANDOFF_M = 0.03
"""Palm origin to bar axis along the door normal: palm skin (0.011) + bar radius (0.011) + 8 mm gap."""
BAR_ALONG_M = 0.125
"""Bar axis distance from the palm origin along the fingers (knuckles at 0.095: the bar lies under the proximal
phalanges, so closing wraps the middle and distal phalanges behind it)."""
PRE_M = 0.08
"""Pre-pose: the grasp pose moved this far out from the door along its normal."""
INSERT_CHECKS = 4
"""IK checks along the straight move from the pre-pose in to the grasp."""
GOAL_MARGIN = 0.12
"""The pull's goal: this fraction of the opening beyond the success condition's fraction."""
TILTS_RAD = (0.0, 0.25, 0.5)
"""Palm tilts about the bar tried (0: palm parallel to the door, the best hook; more brings the forearm closer to
the robot)."""
WRIST_POSTURES = ({"WRJ0": -0.5}, {"WRJ0": 0.0})
"""Hand wrist postures tried with each tilt (``WRJ0`` < 0 bends the back of the hand towards the forearm)."""
CLOSE_FRACTION = 0.4
"""A close aims at this part of the largest open fraction the task allows."""
OVERSHOOT = 0.05
"""The closed loop commands at most this far (rad or m) past its goal."""
JOINT_AT_REACHED = 0.03
"""A move to a ``joint_at`` fraction is done this close to it (a fraction of the joint's range)."""
ARC_CHECK_RAD = 0.05
"""Door-angle spacing of the reachability check along the arc."""
INFLATES_M = (0.01, 0.0)
"""How much the object's link boxes are inflated for the arm while a hook grasp is checked: every candidate with
the first, then with the next."""
ESCAPE_M = 0.15
"""Highest rise of the palm out of the collision model's margins before the open hand is brought to a handle."""
MAX_ARC_JUMP_RAD = 0.35
"""Largest arm-joint change between neighbouring arc samples: more means IK jumped to another branch."""

SOLVED_CATEGORIES = ("cabinet", "microwave", "refrigerator", "drawer_chest")
"""Articulated categories whose main joint these primitives open and close by the handle (side-hinged doors,
drawers; each variant opened on 3-5 seeds). Bottom-hinged doors (oven, dishwasher) are opened by the hook only
near the robot (OpenOvenCompact-v0, the oven at x 0.35 m); at the cabinet's place no hook grasp follows their arc.
Lids (a tab, not a bar), a door being shut (an oven's lying open: lifted by a shelf of bent fingers) and a lever
are pressed instead (:mod:`gendex.solve.press`), when no stage grasps them."""

HOOK_OPEN = {"THJ4": 0.0, "THJ3": 0.0, "THJ2": 0.0, "THJ1": 0.0, "THJ0": 0.0} | {
    f + j: 0.0 for f in ("FF", "MF", "RF", "LF") for j in ("J3", "J2", "J1", "J0")} | {"LFJ4": 0.0}
"""Hand while approaching the bar: fingers straight and together, thumb in the palm plane (away from the door)."""
HOOK_CLOSED = {f + j: v for f in ("FF", "MF", "RF", "LF") for j, v in (("J2", 1.3), ("J1", 1.5), ("J0", 1.5))}
"""Finger closing target of the hook (beyond contact with the bar: the guard stops the fingers on it)."""


# ------------------------------------------------------------------------------------------------------- geometry
def _matrix(pose: sapien.Pose) -> np.ndarray:
    return np.asarray(pose.to_transformation_matrix(), dtype=np.float64)


def _pose(m: np.ndarray) -> sapien.Pose:
    return sapien.Pose(np.asarray(m, dtype=np.float32))


@dataclass(frozen=True)
class JointFrame:
    """Snapshot of one revolute or prismatic joint (one env): where its child link is at any joint position.

    Positive joint motion turns the child right-handed about ``axis`` through ``point``, or slides it along ``axis``
    (PhysX: the x axis of the joint frame).
    """

    point: np.ndarray
    """[3] a point on the hinge axis, world."""
    axis: np.ndarray
    """[3] unit hinge axis, world."""
    q: float
    """Joint position when read."""
    link: np.ndarray
    """[4, 4] child link pose (world) when read."""
    prismatic: bool = False
    """A slide (a drawer): joint positions are metres along ``axis``."""

    def link_at(self, q: float) -> np.ndarray:
        """[4, 4] world pose of the child link at joint position ``q``."""
        m = np.eye(4)
        if self.prismatic:
            m[:3, 3] = (q - self.q) * self.axis
            return m @ self.link
        m[:3, :3] = axis_rotation(self.axis, q - self.q)
        m[:3, 3] = self.point - m[:3, :3] @ self.point
        return m @ self.link

    def point_at(self, local: np.ndarray, q: float) -> np.ndarray:
        """[3] world position at joint position ``q`` of a point fixed at ``local`` in the child link's frame."""
        m = self.link_at(q)
        return m[:3, :3] @ np.asarray(local, dtype=np.float64) + m[:3, 3]


def read_joint(env: TaskEnv, name: str, env_idx: int = 0) -> JointFrame:
    """The main joint of articulated object ``name`` in env ``env_idx``, as simulated now."""
    art = env.articulations[name]
    joint = art.get_active_joints()[env.joint_index(name)]
    px = px_objects(joint)[env_idx]  # PhysX's own joint pose
    if px.type not in ("revolute", "revolute_unwrapped", "prismatic"):
        raise ExecutionError(f"{name!r}: joint {joint.name!r} is {px.type}; the articulated primitives move "
                             f"revolute (doors, lids) and prismatic (drawers) joints only", cause="unsupported")
    frame = _matrix(px.get_global_pose())
    pose = env.handle_link(name).pose
    link = _matrix(sapien.Pose(pose.p[env_idx].cpu().numpy(), pose.q[env_idx].cpu().numpy()))
    return JointFrame(point=frame[:3, 3].copy(), axis=frame[:3, 0] / np.linalg.norm(frame[:3, 0]),
                      q=float(env.joint_qpos(name)[env_idx]), link=link, prismatic=px.type == "prismatic")


def link_pose(link) -> np.ndarray:
    """[4, 4] world pose of a ManiSkill link (first sub-scene)."""
    pose = link.pose
    return sapien.Pose(pose.p[0].cpu().numpy(), pose.q[0].cpu().numpy()).to_transformation_matrix()


def handle_local(env: TaskEnv, name: str) -> np.ndarray:
    """[3] grip point of ``name``'s handle in its link frame (scaled)."""
    jr = env.joint_record(name)
    return np.asarray(jr.handle_point_m, dtype=np.float64) * env.task_spec.object(name).scale


@dataclass(frozen=True)
class LinkGrip:
    """Palm pose fixed in a moving link's frame; it follows the link along its path (a hook, a press)."""

    offset: np.ndarray
    """[4, 4] palm pose in the link frame."""
    normal_local: np.ndarray
    """[3] unit direction in the link frame along which the pre-pose backs off (a door's outward normal)."""

    def palm_at(self, joint: JointFrame, q: float, out_m: float = 0.0) -> sapien.Pose:
        """World palm pose at joint position ``q``, backed off ``out_m`` along :attr:`normal_local`."""
        m = joint.link_at(q) @ self.offset
        m[:3, 3] += out_m * (joint.link_at(q)[:3, :3] @ self.normal_local)
        return _pose(m)


@dataclass(frozen=True)
class HookGrasp(LinkGrip):
    """A hook of the handle bar: fingers straight across it, then curled behind it."""

    to_hinge: bool = True
    """Fingers point towards the hinge (else towards the free edge)."""
    tilt_rad: float = 0.0
    """Palm turned about the bar's axis away from parallel to the door (fingers into the door, forearm out)."""
    wrist: dict[str, float] = field(default_factory=dict)
    """Hand wrist joint targets held during the grasp (extension lets the forearm come from the front)."""

    def __str__(self) -> str:
        side = "hinge" if self.to_hinge else "free edge"
        return f"hook grasp (fingers towards the {side}, tilt {self.tilt_rad:.2f} rad, wrist {self.wrist})"


def hook_grasps(joint: JointFrame, handle: np.ndarray) -> list[HookGrasp]:
    """Hook grasps of a bar parallel to the hinge axis through ``handle`` (link frame), in order of preference:
    fingers towards the hinge first, then towards the free edge; for each, every tilt of :data:`TILTS_RAD` with
    every wrist posture of :data:`WRIST_POSTURES`."""
    link = joint.link
    rot_t = link[:3, :3].T
    n = DOOR_FRONT_LOCAL
    if joint.prismatic:  # a drawer: a horizontal bar across its front; fingers down over it first, then up
        up = rot_t @ np.array([0.0, 0.0, 1.0])
        axis = np.cross(up, n)
        axis /= np.linalg.norm(axis)
        radial = up  # "towards the hinge" below means fingers down
    else:
        axis = rot_t @ joint.axis
        hinge = rot_t @ (joint.point - link[:3, 3])
        radial = handle - hinge
        radial -= np.dot(radial, axis) * axis  # from the hinge axis to the bar, perpendicular to it
    out = []
    for to_hinge in (True, False):
        f = -radial if to_hinge else radial
        f = f - np.dot(f, n) * n - np.dot(f, axis) * axis  # along the door's front, across the bar
        f /= np.linalg.norm(f)
        m = np.eye(4)
        m[:3, :3] = palm_rotation(f, -n)
        m[:3, 3] = handle + PALM_STANDOFF_M * n - BAR_ALONG_M * f
        # turning about the bar keeps the bar where it is in the palm frame; the sign turns the fingers into the door
        sign = 1.0 if np.dot(axis_rotation(axis, 0.1) @ f, n) < 0 else -1.0
        for tilt in TILTS_RAD:
            r = np.eye(4)
            r[:3, :3] = axis_rotation(axis, sign * tilt)
            r[:3, 3] = handle - r[:3, :3] @ handle
            for wrist in WRIST_POSTURES:
                out.append(HookGrasp(r @ m, n.copy(), to_hinge, tilt, dict(wrist)))
    return out


def joint_target(env: TaskEnv, name: str) -> float | None:
    """The fraction a ``joint_at`` success condition puts ``name``'s joint at (*open the drawer halfway*), else
    None."""
    return next((c.fraction for c in env.task_spec.success.conditions
                 if c.type == "joint_at" and c.object == name and not c.negate and c.fraction is not None), None)


def opening_goal(env: TaskEnv, name: str) -> float:
    """Joint position the pull aims for: the success condition's open fraction plus :data:`GOAL_MARGIN`, or the
    ``joint_at`` condition's fraction itself."""
    target = joint_target(env, name)
    if target is not None:
        return _clip_joint(env, name, target)
    fractions = [c.min_fraction for c in env.task_spec.success.conditions
                 if c.type == "joint_open" and c.object == name and c.min_fraction is not None and not c.negate]
    frac = max(fractions) if fractions else 1.0
    return _clip_joint(env, name, frac + GOAL_MARGIN)


def closing_goal(env: TaskEnv, name: str, part: float = CLOSE_FRACTION) -> float:
    """Joint position a close aims for: ``part`` of the open fraction a negated ``joint_open`` condition still
    allows (short of the closed end, where the hand would hit the body), or a ``joint_at`` condition's fraction."""
    target = joint_target(env, name)
    if target is not None:
        return _clip_joint(env, name, target)
    fractions = [c.min_fraction for c in env.task_spec.success.conditions
                 if c.type == "joint_open" and c.object == name and c.min_fraction is not None and c.negate]
    frac = min(fractions) if fractions else 0.1
    return _clip_joint(env, name, part * frac)


def _clip_joint(env: TaskEnv, name: str, fraction: float) -> float:
    """The joint position at ``fraction`` of the way from closed to open, kept off the limits."""
    closed, opened = env.closed_qpos(name), env.open_qpos(name)
    lo, hi = env.articulations[name].get_qlimits()[0, env.joint_index(name)].tolist()
    margin = 0.02 if env.joint_record(name).type == "revolute" else 0.004
    return float(np.clip(closed + fraction * (opened - closed), lo + margin, hi - margin))


# ------------------------------------------------------------------------------------------------------ primitives
@dataclass
class HandleConfig:
    """Speeds and checks of the articulated primitives (control steps at 20 Hz)."""

    rate_rad: float = 0.04
    """Door angle the palm target advances per control step (0.8 rad/s: the door never outruns the hand)."""
    lead_rad: float = 0.1
    """The palm target runs at most this far ahead of the measured door angle."""
    max_steps: int = 160
    stall_steps: int = 12
    """The door moving less than ``stall_rad`` over this many steps ends the pull (hook slipped)."""
    stall_rad: float = 0.01
    rate_m: float = 0.008
    lead_m: float = 0.03
    stall_m: float = 0.005
    """The same for a slide (a drawer), in metres."""
    close_steps: int = 10
    squeeze_steps: int = 4
    insert_m_per_step: float = 0.012


class HandlePrimitives:
    """The articulated primitives of one episode, built on the executor's :class:`ArmHandMotion`; ``hand_cover``
    gives the sphere cover (palm frame) of the open hand, or of the hand at the joint targets it is given, that the
    arm's collision model carries while it brings the hand to the part (None: the arm alone)."""

    def __init__(self, motion: ArmHandMotion, config: HandleConfig | None = None,
                 hand_cover: Callable[..., tuple[np.ndarray, np.ndarray]] | None = None):
        self.motion = motion
        self.config = config or HandleConfig()
        self.hand_cover = hand_cover
        self.grasp: HookGrasp | None = None
        self.hooked = False
        self.target: str | None = None
        self._shapes: dict[tuple[str, str], ObjectShape | None] = {}
        self._others: list[Box] = []
        """Boxes of the scene's other objects, obstacles beside the part's own (:meth:`_clear_of_others`)."""

    def run(self, prim: str, stage) -> Iterator[np.ndarray]:
        """The actions of primitive ``prim`` (``approach_handle``, ``hook``, ``pull`` or ``shut``) for ``stage``."""
        if prim not in ("approach_handle", "hook", "pull", "shut"):
            raise ExecutionError(f"no articulated primitive {prim!r}; primitives: approach_handle, hook, pull, shut",
                                 cause="unsupported")
        return getattr(self, prim)(stage)

    def _obstacles(self, boxes: list[Box]) -> None:
        """Plan among ``boxes`` (the part's) and the other objects' boxes, if :meth:`_clear_of_others` set them."""
        self.motion.collision.set_obstacles(boxes + self._others)

    def _clear_of_others(self, name: str, search: Callable[[], T | None]) -> T | None:
        """``search()`` (for a grasp or press pose of ``name``'s part, and the arm motions it needs) run with every
        other object an obstacle too, and again without them only if that finds nothing. Without them the forearm,
        swung along a microwave door's arc, knocked a standing bottle over (a fresh batch's close-the-door-then-set-
        the-bottle-down task, dev seeds 779401-779403: the bottle was then too low to grasp)."""
        others = self.motion.object_boxes(exclude=(name,))
        for boxes in ((others, []) if others else ([],)):  # without others the second pass would repeat the first
            self._others = boxes
            found = search()
            if found is not None:
                return found
            if self._others:
                log.info("%r: no pose of the hand and arm clear of the other objects; trying without them", name)
        return None

    def _goal(self, name: str) -> float:
        """Where this task moves ``name``'s joint: towards closed if a stage closes it, else open."""
        u = self.motion.env
        closes = any(s.skill == "close" and s.target == name for s in u.task_spec.stages)
        return closing_goal(u, name) if closes else opening_goal(u, name)

    def mark_hooked(self, target: str) -> None:
        """Record that the fingers hold ``target``'s handle (a trained grasp policy hooked it)."""
        self.hooked, self.target = True, target

    # ------------------------------------------------------------------ helpers
    def _boxes(self, name: str, moving: bool, inflate_m: float = 0.01) -> list[Box]:
        """World boxes of the object's links (without the handle link when ``moving``), inflated ``inflate_m``."""
        u = self.motion.env
        handle = u.handle_link(name).name
        boxes = []
        for link in u.articulations[name].get_links():
            if moving and link.name == handle:
                continue
            aabb = px_objects(link)[0].compute_global_aabb_tight()  # PhysX's tight box
            lo, hi = np.asarray(aabb, dtype=np.float64)
            boxes.append(Box(lo - inflate_m, hi + inflate_m, f"{name}/{link.name}"))
        return boxes

    def _link_shape(self, name: str, link) -> ObjectShape | None:
        """Convex parts of ``name``'s link ``link`` in its own frame (cached; None for a link without collision
        shapes)."""
        key = (name, link.name)
        if key not in self._shapes:
            try:
                self._shapes[key] = ObjectShape.of_actor(link)
            except ValueError:
                self._shapes[key] = None
        return self._shapes[key]

    def _shape(self, name: str) -> ObjectShape:
        """The moving link's convex parts, in its own frame."""
        link = self.motion.env.handle_link(name)
        shape = self._link_shape(name, link)
        if shape is None:
            raise ExecutionError(f"{name!r}: the moving link {link.name!r} has no collision shapes",
                                 cause="unsupported")
        return shape

    def _fixed_shapes(self, name: str) -> list[PosedShape]:
        """World shapes of ``name``'s links that the pressed joint does not move."""
        moving = self.motion.env.handle_link(name).name
        links = [k for k in self.motion.env.articulations[name].get_links() if k.name != moving]
        return [shape.posed(link_pose(link)) for link in links
                if (shape := self._link_shape(name, link)) is not None]

    def _part_boxes(self, name: str) -> list[Box]:
        """Obstacles while the open hand comes to the part: the fixed links' boxes and the moving link's convex
        parts, each covered by small boxes along it (:func:`~gendex.solve.collision.rotated_box_cover`: not one box
        over the wedge a swung door spans), all inflated 1 cm."""
        boxes = self._boxes(name, moving=True)
        link = self.motion.env.handle_link(name)
        m = link_pose(link)
        for part in self._shape(name).parts:
            boxes += rotated_box_cover(part.vertices.min(axis=0), part.vertices.max(axis=0), m, 0.01,
                                       name=f"{name}/{link.name}")
        return boxes

    def _chain(self, poses: list[sapien.Pose], q: np.ndarray, restarts: int = 0) -> np.ndarray | None:
        """IK chained through ``poses`` from ``q`` (each solve seeded with the last, then from ``restarts`` random
        starts); None when a pose has no solution, the arm jumps branches (:data:`MAX_ARC_JUMP_RAD`) or a
        configuration collides."""
        ex = self.motion
        for pose in poses:
            nq = ex.ik.solve(pose, q, restarts=restarts)
            if nq is None or np.max(np.abs(nq[ex.ik.arm] - q[ex.ik.arm])) > MAX_ARC_JUMP_RAD \
                    or not ex.collision.is_free(nq):
                return None
            q = nq
        return q

    def _arc(self, grasp: LinkGrip, joint: JointFrame, goal: float) -> list[sapien.Pose]:
        """Palm poses along the door's arc from its angle now to ``goal``, :data:`ARC_CHECK_RAD` apart."""
        n = max(1, int(np.ceil(abs(goal - joint.q) / ARC_CHECK_RAD)))
        return [grasp.palm_at(joint, joint.q + (goal - joint.q) * k / n) for k in range(1, n + 1)]

    # ------------------------------------------------------------------ primitives
    def approach_handle(self, stage) -> Iterator[np.ndarray]:
        ex, name = self.motion, stage.target
        u = ex.env
        joint = read_joint(u, name)
        handle = handle_local(u, name)
        goal = self._goal(name)
        chosen = self._clear_of_others(name, lambda: self._find_hook(name, joint, handle, goal))
        if chosen is None:
            raise ExecutionError(f"no hook grasp of {name!r}'s handle that the arm can reach and pull along the "
                                 f"door's arc", cause="no_ik")
        grasp, q_pre, q0, inflate = chosen
        log.info("%r: %s", name, grasp)
        self.grasp, self.target, self.hooked = grasp, name, False
        yield from self._bring_open_hand(name, q_pre, q0, inflate)
        normal = joint.link[:3, :3] @ grasp.normal_local
        yield from ex.cartesian(-PRE_M * normal, self.config.insert_m_per_step)
        yield from ex.settle()

    def _find_hook(self, name: str, joint: JointFrame, handle: np.ndarray, goal: float) -> tuple | None:
        """The first hook grasp (with its pre-pose joints, hand joints and inflation) whose pre-pose the arm
        reaches, that it moves straight in from, and whose arc to ``goal`` it follows, all clear of the obstacles."""
        ex = self.motion
        # the links' boxes inflated 1 cm first; where no grasp clears them (a low drawer: the forearm housing
        # passes 1.5 cm from the chest's front), the links' own boxes (the model's 2 cm margin still applies)
        for inflate in INFLATES_M:
            for grasp in hook_grasps(joint, handle):
                q0 = ex.with_hand(ex.target(), HOOK_OPEN | grasp.wrist)
                self._obstacles(self._boxes(name, moving=False, inflate_m=inflate))
                q_pre = ex.ik.solve(grasp.palm_at(joint, joint.q, PRE_M), q0, restarts=20,
                                    valid=ex.collision.is_free)
                if q_pre is None:
                    log.debug("%s: pre-pose unreachable", grasp)
                    continue
                n = INSERT_CHECKS
                q_in = self._chain([grasp.palm_at(joint, joint.q, PRE_M * (1 - k / n)) for k in range(1, n + 1)],
                                   q_pre)
                if q_in is None:
                    log.debug("%s: no straight motion in", grasp)
                    continue
                self._obstacles(self._boxes(name, moving=True, inflate_m=inflate))
                if self._chain(self._arc(grasp, joint, goal), q_in) is None:
                    log.debug("%s: arm cannot follow the arc", grasp)
                    continue
                return grasp, q_pre, q0, inflate
        return None

    def _bring_open_hand(self, name: str, q_pre: np.ndarray, q0: np.ndarray, inflate_m: float = 0.01
                         ) -> Iterator[np.ndarray]:
        """Planned arm motion to the pre-pose ``q_pre`` with the open hand (targets ``q0``) in the collision model
        among the part's boxes (:meth:`_part_boxes`), after the palm rose clear of what the resting hand touches (an
        oven put beside the rest pose: dragged across it, the fingers caught on the door's bar); the arm alone
        among the links' boxes (inflated ``inflate_m``) when that finds no path."""
        ex = self.motion
        path, rise = None, 0.0
        if self.hand_cover is not None:
            self._obstacles(self._part_boxes(name))
            ex.collision.cover_hand(*self.hand_cover())
            try:
                rise, start = ex.rise_clear(q0, ESCAPE_M)
                path = ex.plan_arm(q_pre, hand=q0, start=start)
            except ExecutionError as exc:
                log.debug("no path with the open hand covered (%s): planning the arm alone", exc)
                path, rise = None, 0.0
            finally:
                ex.collision.cover_hand(None)
        self._obstacles(self._boxes(name, moving=False, inflate_m=inflate_m))
        if path is None:
            yield from ex.move_arm(q_pre, hand=q0)
            return
        if rise > 0:
            yield from ex.cartesian(np.array([0.0, 0.0, rise]), self.config.insert_m_per_step)
        yield from path

    def hook(self, stage) -> Iterator[np.ndarray]:
        ex, c = self.motion, self.config
        if self.grasp is None or self.target != stage.target:
            yield from self.approach_handle(stage)
        closed = ex.with_hand(ex.target(), HOOK_CLOSED)
        yield from ex.ramp(closed, c.close_steps, guard=True)
        for _ in range(c.squeeze_steps):
            yield ex.emit(closed, guard=True)
        self.hooked = True

    def pull(self, stage) -> Iterator[np.ndarray]:
        """Open the hooked door or drawer to :func:`opening_goal` along its path."""
        yield from self._move_joint(stage, opening_goal(self.motion.env, stage.target), 1.0)

    def shut(self, stage) -> Iterator[np.ndarray]:
        """Close the hooked door or drawer to :func:`closing_goal` along its path (the hook pushes it back)."""
        yield from self._move_joint(stage, closing_goal(self.motion.env, stage.target), -1.0)

    def _move_joint(self, stage, goal: float, sign: float, hand: dict[str, float] | None = None,
                    lead: float | None = None) -> Iterator[np.ndarray]:
        """Move the joint towards ``goal`` (``sign`` +1: opening, -1: closing) with the palm on :attr:`grasp`'s
        path: hooked (``hand`` None: the hook is closed first if it is not) or pressing with the hand held at
        ``hand``. ``lead`` overrides how far the command may run ahead of the measured joint position. Done at
        once if the joint is already there (approaching an open drawer may have pushed it shut)."""
        ex, c, name = self.motion, self.config, stage.target
        if hand is None and (not self.hooked or self.target != name):
            yield from self.hook(stage)
        u = ex.env
        closed = ex.with_hand(ex.target(), HOOK_CLOSED if hand is None else hand)
        how = "the hook slipped off the handle" if hand is None else "the hand lost contact with it"
        history: list[float] = []
        joint = read_joint(u, name)
        q_cmd = joint.q
        rate, default_lead, stall = ((c.rate_m, c.lead_m, c.stall_m) if joint.prismatic else
                                     (c.rate_rad, c.lead_rad, c.stall_rad))
        lead = default_lead if lead is None else lead
        # a joint_at goal is where the part must stay: the command stops there and the loop ends once the joint is
        # within JOINT_AT_REACHED of it (the hand, still on the part, keeps it there)
        exact = joint_target(u, name) is not None
        beyond = 0.0 if exact else OVERSHOOT
        near = JOINT_AT_REACHED * abs(u.open_qpos(name) - u.closed_qpos(name)) if exact else 0.0
        for _ in range(c.max_steps):
            joint = read_joint(u, name)
            history.append(joint.q)
            if sign * (joint.q - goal) >= -near:
                log.info("joint of %r at %.3f (goal %.3f)", name, joint.q, goal)
                return
            if len(history) > c.stall_steps and sign * (history[-1] - history[-1 - c.stall_steps]) < stall:
                raise ExecutionError(f"the joint of {name!r} stalled at {joint.q:.3f} (goal {goal:.3f}): {how}",
                                     cause="slipped")
            target = ex.target()
            # the command advances at most ``rate`` a step and runs at most ``lead`` ahead of the measured position
            q_next = sign * min(sign * q_cmd + rate, sign * joint.q + lead, sign * goal + beyond)
            q = ex.ik.solve(self.grasp.palm_at(joint, q_next), target, restarts=0)
            if q is None:
                raise ExecutionError(f"no IK for the palm on {name!r}'s path at {q_next:.3f}", cause="no_ik")
            # where the arm must turn fast for the palm to keep up, the command slows down instead (a uniform scale
            # of the joint step keeps the palm on the path; a per-joint clip would not)
            delta = q[ex.ik.arm] - target[ex.ik.arm]
            scale = min(1.0, ex.max_arm_step_rad / max(float(np.max(np.abs(delta))), 1e-9))
            q_cmd += (q_next - q_cmd) * scale
            t = closed.copy()
            t[ex.ik.arm] = target[ex.ik.arm] + scale * delta
            yield ex.emit(t, guard=True)
        raise ExecutionError(f"the joint of {name!r} reached {read_joint(u, name).q:.3f} of {goal:.3f} in "
                             f"{c.max_steps} steps", cause="target_not_reached")


__all__ = ["HOOK_CLOSED", "HOOK_OPEN", "SOLVED_CATEGORIES", "HandleConfig", "HandlePrimitives", "HookGrasp",
           "JointFrame", "LinkGrip", "closing_goal", "handle_local", "hook_grasps", "joint_target", "opening_goal",
           "read_joint"]
