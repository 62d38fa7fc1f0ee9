"""Contact moves of articulated parts: push a door shut, a lid up by its tab or down past its hinge, a tap's lever
round, with the flat hand and no grasp.

A hinged part whose stages never grasp it is moved by *pressing*: the hand touches the moving link on the side the
motion comes from and follows the part's own path (:class:`~gendex.solve.articulated.JointFrame`), every control
step placing the palm where the contact will be a little further along, so the part is pushed ahead of the hand.
Two primitives, run by :class:`~gendex.solve.executor.StageExecutor` (skills ``reach``, then ``open``, ``close``
or ``turn``):

- ``approach_press`` — reads the joint from the live articulation, finds where the part's surface is on the push
  side of its grip point (a ray against the link's PhysX convex parts), and synthesizes *press poses*: the palm
  faces the direction the contact must move, with its centre (or, for a tab, the fingertips) on that surface,
  the fingers pointing any of eight ways about the push, the palm turning with the part or with half its turn. A
  pose is kept only if the open hand clears the fixed links and the table along the path, the arm reaches its
  pre-pose (:data:`PRE_M` back from the surface) with the open hand clear of the whole part, and the arm can
  follow the contact along the whole path to the goal (IK chained along sampled joint positions, collision-checked
  against the fixed links). The arm is planned to the pre-pose with the open hand in its collision model and
  moves straight in.
- ``press`` — closed loop along the path, as :meth:`~gendex.solve.articulated.HandlePrimitives.pull` runs a hooked
  handle, with the hand open: the target runs ahead of the measured joint position, so the palm keeps pushing.

Which way a stage moves the joint: ``open`` opens it, ``close`` closes it, and ``turn`` goes where the task's
``joint_open`` condition on the target points (opening unless the condition is negated).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

import numpy as np
import sapien

from gendex.solve.articulated import (
    ARC_CHECK_RAD,
    HOOK_OPEN,
    OVERSHOOT,
    HandlePrimitives,
    JointFrame,
    LinkGrip,
    closing_goal,
    handle_local,
    opening_goal,
    read_joint,
)
from gendex.solve.grasp import axis_rotation, palm_rotation
from gendex.solve.shape import ObjectShape, PosedShape
from gendex_envs.errors import ExecutionError
from gendex_envs.physx import px_bodies
from gendex_envs.spec import JOINT_SKILLS

log = logging.getLogger(__name__)

PALM_CONTACT = np.array([0.0, -0.0135, 0.045])
"""Palm frame point that touches the surface in a palm press: the skin at the palm's centre (the sphere cover of
the open hand: palm skin at y = -13.3 mm, the palm spans z = 0 to 0.09)."""
FINGER_CONTACT = np.array([0.0, -0.010, 0.18])
"""Palm frame point that touches the surface in a fingertip press: the middle finger's skin at its pad, fingers
straight (the finger pads lie at z = 0.174 to 0.185; the tips end 2 cm further)."""
SHELF_HAND = HOOK_OPEN | {"FFJ2": 1.57, "MFJ2": 1.57, "RFJ2": 1.57, "LFJ2": 1.2, "LFJ1": 1.57, "LFJ0": 1.57}
"""A shelf: the fingers bent square at their knuckles, straight beyond (the little finger curled out of the way),
the thumb in the palm plane."""
POKE_HAND = HOOK_OPEN | {f + j: v for f in ("MF", "RF", "LF") for j, v in (("J3", 1.55), ("J2", 1.55), ("J1", 1.4),
                                                                          ("J0", 1.4))} | {
    "THJ4": 1.2, "THJ3": 0.2, "THJ2": 0.2, "THJ1": 0.8, "THJ0": 0.8}
"""A poke: the index finger straight, the other fingers curled into the palm, the thumb folded across it (their
lowest points 9 cm behind the index tip)."""
POKE_TILTS_DEG = (0, 25, 40)
"""How far a poking finger may lean off the push direction (the wrist then sits nearer the robot: a finger straight
down over a button 1.2 m from the arm's base leaves the wrist out of reach)."""
POKE_CONTACT = np.array([0.033, 0.0, 0.195])
"""Palm frame point that touches in a poke: the end of the straight index finger (its tip site at z = 0.191)."""
SHELF_CONTACT = np.array([0.011, -0.085, 0.091])
"""Palm frame point that touches the surface in a shelf lift: the top of the bent middle finger 1.6 cm from its
tip (its axis at z = 0.099, radius 7-8 mm; the fingers end at y = -0.101)."""
SHELF_FOLLOWS = (-0.5, -0.25, 0.0)
"""How much of the part's turn a shelf's palm takes on: turning against the part (-0.5) tips the fingers into it
as it rises and keeps the wrist near the robot; a palm kept level (0) left the arm stretched straight before a
bottom-hinged oven door was shut (no IK below 0.14 rad)."""
CONTACT_GAP_M = 0.008
"""The press pose stops this short of the surface; the closed loop then pushes."""
PRESS_LEAD_M = 0.03
"""The palm's target runs this far (at the contact, along the path) ahead of where the part is."""
HANDOVER_MARGIN_RAD = 0.15
"""A press that gravity can finish goes on this far past the point where gravity starts to help enough."""
HANDOVER_TORQUE_FRACTION = 0.5
"""Gravity helps enough where its torque towards the goal is at least this part of its largest on the way (joint
friction holds a lid that is just past upright: measured, a bin lid let go at 1.3 rad stays, at 1.0 rad falls)."""
STAY_MARGIN_RAD = 0.08
"""A lid that must stay open is pushed this far past its balance point (gravity and the push's momentum carry it on to
its stop)."""
RETREAT_M = 0.08
"""After a handover the palm backs off this far against the push direction and rises as much."""
FALL_STEPS = 40
"""Control steps the part gets to fall the rest of the way to the goal after the hand let go (2 s)."""
PRE_M = (0.08, 0.14, 0.05)
"""Pre-poses tried in turn until the arm reaches one with the open hand clear and can move straight in from it: the
press pose backed off this far from the surface (the further one for where the open hand at the nearer one would
touch the part; the nearest where the arm, reaching in close to its base, has no straight path from the others: a
shelf under a large box's tab at x = 0.50, composed batch 73019, 6/10 -> 8/10 dev seeds)."""
PRESS_CLOSE_FRACTION = 0.85
"""A press that closes aims at this part of the open fraction the task's negated ``joint_open`` allows (the
closed end is where the arm has the least room)."""
FINGER_ANGLES_DEG = (0, 90, 45, -45, 135, 180, -90, -135)
"""Finger directions tried, turned about the push direction from the hinge axis (positive: towards the hinge)."""
FOLLOWS = (1.0, 0.5)
"""How much of the part's turn the palm takes on (:attr:`PressPose.follow`), in order of preference."""
SHIFTS_M = ((0.0, 0.0), (0.08, 0.0), (-0.08, 0.0), (0.0, 0.012), (0.0, 0.025), (0.0, -0.06))
"""Contact points tried: the grip point moved (along the hinge axis, away from the axis) by these distances (a
door's bar is one place to push it, the door above and below the bar are others; a lever is pushed near its end
or nearer its hub)."""
INSERT_STEP_M = 0.02
"""IK checks along the straight move in, this far apart."""
HAND_CLEAR_M = 0.005
"""The open hand keeps this far off the parts the press does not move (and the table) along the whole path."""
CHAIN_RESTARTS = 3
"""Random IK restarts where the seeded solve fails along the path (the jump limit still rejects another branch)."""
RAY_BACK_M = 0.3
"""The surface ray starts this far behind the grip point, on the hand's side."""


@dataclass(frozen=True)
class PressPose(LinkGrip):
    """A palm pose fixed in the moving link's frame that touches the link, ready to push it."""

    site: str = "palm"
    """What touches: the ``palm`` centre or the ``fingers`` near their tips."""
    fingers: str = ""
    """Where the fingers point, in words (for logs)."""
    back: str = ""
    """How the pre-pose backs off, in words (for logs)."""
    shift_m: tuple[float, float] = (0.0, 0.0)
    """Where the contact is: the grip point moved this far along the hinge axis and away from it."""
    follow: float = 1.0
    """How much of the part's turn the palm takes on along the path (1: fixed to the link; 0.5: half, the palm's
    edge then leads; a slide's palm never turns)."""
    q_ref: float = 0.0
    """Joint position at which :attr:`offset` was computed (where the palm faces the surface square on)."""
    contact: np.ndarray = field(default_factory=lambda: PALM_CONTACT.copy())
    """[3] palm frame point that touches the part."""
    hand: dict[str, float] = field(default_factory=lambda: dict(HOOK_OPEN))
    """Hand joint targets while the pose is brought in and pushes (the open hand, or a shelf)."""

    def palm_at(self, joint: JointFrame, q: float, out_m: float = 0.0) -> sapien.Pose:
        pose = super().palm_at(joint, q, out_m)
        if self.follow == 1.0 or joint.prismatic:
            return pose
        m = pose.to_transformation_matrix()
        touch = m[:3, :3] @ self.contact + m[:3, 3]  # the contact point stays where the link puts it
        m[:3, :3] = axis_rotation(joint.axis, -(1.0 - self.follow) * (q - self.q_ref)) @ m[:3, :3]
        m[:3, 3] = touch - m[:3, :3] @ self.contact
        return sapien.Pose(np.asarray(m, dtype=np.float32))

    def __str__(self) -> str:
        if self.site == "shelf":
            return (f"shelf lift at the grip point {self.shift_m[0]:+.2f} m along the axis and "
                    f"{self.shift_m[1]:+.2f} m out (following {self.follow:.2f} of the turn)")
        return (f"press with the {self.site} at the grip point {self.shift_m[0]:+.2f} m along the axis and "
                f"{self.shift_m[1]:+.2f} m out (fingers "
                f"{self.fingers}, following {self.follow:.1f} of the turn, backing off {self.back})")


def press_direction(joint: JointFrame, point_local: np.ndarray) -> np.ndarray:
    """[3] unit direction (link frame) in which the point ``point_local`` of the moving link goes when the joint
    opens (positive motion)."""
    rot_t = joint.link[:3, :3].T
    axis = rot_t @ joint.axis
    if joint.prismatic:
        return axis
    radial = np.asarray(point_local, float) - rot_t @ (joint.point - joint.link[:3, 3])
    t = np.cross(axis, radial)
    n = float(np.linalg.norm(t))
    if n < 1e-6:
        raise ExecutionError("the grip point lies on the hinge axis: pressing there cannot turn the part",
                             cause="unsupported")
    return t / n


def press_poses(joint: JointFrame, shape: ObjectShape, point_local: np.ndarray, sign: float,
                shelf_first: bool = False, poke_first: bool = False) -> list[PressPose]:
    """Press poses of the moving link (its convex ``shape`` in the link frame) that push the point ``point_local``
    (moved by each of :data:`SHIFTS_M`) towards opening (``sign`` +1) or closing (-1), in order of preference: palm
    presses before fingertip presses before shelf lifts (``shelf_first``: shelf lifts before fingertip presses;
    ``poke_first``: index-finger pokes before all of them, a button's or switch's press, where the open hand would
    push whatever lies under its 20 cm);
    then by contact point; fingers as :data:`FINGER_ANGLES_DEG` orders them; the palm following as :data:`FOLLOWS`
    does."""
    rot_t = joint.link[:3, :3].T
    axis = rot_t @ joint.axis
    posed = shape.posed(np.eye(4))
    contacts = []  # (surface point, motion direction there)
    hinge = rot_t @ (joint.point - joint.link[:3, 3])
    for shift, out_m in SHIFTS_M:
        p = np.asarray(point_local, float) + shift * axis
        if out_m:
            if joint.prismatic:
                continue
            radial = p - hinge - np.dot(p - hinge, axis) * axis
            p = p + out_m * radial / max(float(np.linalg.norm(radial)), 1e-9)
        m = sign * press_direction(joint, p)
        spans = posed.ray_intervals(p - RAY_BACK_M * m, m)
        if spans and spans[0][0] < RAY_BACK_M + 0.05:
            surface = p - RAY_BACK_M * m + spans[0][0] * m
            contacts.append((surface, sign * press_direction(joint, surface), (shift, out_m)))
    if not contacts:
        raise ExecutionError("no surface of the moving part on the line through its grip point", cause="unsupported")
    out = []
    for site, contact in (("palm", PALM_CONTACT), ("fingers", FINGER_CONTACT)):
        for surface, m, shift in contacts:
            base = axis - np.dot(axis, m) * m
            if np.linalg.norm(base) < 1e-6:  # a slide pushed along its axis: start from the vertical
                base = np.array([0.0, 0.0, 1.0]) - m[2] * m
            if np.linalg.norm(base) < 1e-6:  # pushed straight down (a button): start from the link's x
                base = np.array([1.0, 0.0, 0.0]) - m[0] * m
            base /= np.linalg.norm(base)
            if not joint.prismatic:  # positive angles turn the fingers towards the hinge
                hinge = rot_t @ (joint.point - joint.link[:3, 3])
                if np.dot(np.cross(m, base), hinge - surface) < 0:
                    m_turn = -m
                else:
                    m_turn = m
            else:
                m_turn = m
            for deg in FINGER_ANGLES_DEG:
                f = axis_rotation(m_turn, np.radians(deg)) @ base
                words = f"{deg:+d} deg from the hinge axis"
                rot = palm_rotation(f, m)
                off = np.eye(4)
                off[:3, :3] = rot
                off[:3, 3] = surface - CONTACT_GAP_M * m - rot @ contact
                backs = [(-m, "from the surface")] + ([(-f, "along the fingers")] if site == "fingers" else [])
                for back, how in backs:
                    for follow in FOLLOWS:
                        out.append(PressPose(off, back.copy(), site=site, fingers=words, back=how, shift_m=shift,
                                             follow=follow, q_ref=joint.q, contact=contact.copy()))
    if poke_first:
        out = poke_poses(joint, contacts) + out
    if not joint.prismatic:
        shelves = shelf_poses(joint, contacts)
        if shelf_first:
            palm = [p for p in out if p.site == "palm"]
            return palm + shelves + [p for p in out if p.site != "palm"]
        out += shelves
    return out


def poke_poses(joint: JointFrame, contacts: list[tuple[np.ndarray, np.ndarray, tuple[float, float]]]
               ) -> list[PressPose]:
    """Index-finger pokes at each contact: the straight finger along the push, the palm facing each of eight ways
    about it; the finger backs off along itself."""
    out = []
    for surface, m, shift in contacts:
        base = np.array([1.0, 0.0, 0.0]) - m[0] * m
        if np.linalg.norm(base) < 1e-6:
            base = np.array([0.0, 1.0, 0.0]) - m[1] * m
        base /= np.linalg.norm(base)
        for tilt in POKE_TILTS_DEG:
            for deg in FINGER_ANGLES_DEG:
                h = axis_rotation(m, np.radians(deg)) @ base
                t = np.radians(tilt)
                f = np.cos(t) * m - np.sin(t) * h  # the finger leans away from where the palm faces
                n = h - np.dot(h, f) * f
                rot = palm_rotation(f, n / np.linalg.norm(n))
                off = np.eye(4)
                off[:3, :3] = rot
                off[:3, 3] = surface - CONTACT_GAP_M * m - rot @ POKE_CONTACT
                out.append(PressPose(off, -f, site="poke", fingers=f"palm facing {deg:+d} deg, leaning {tilt} deg",
                                     back="along the finger", shift_m=shift, q_ref=joint.q,
                                     contact=POKE_CONTACT.copy(), hand=dict(POKE_HAND)))
    return out


def shelf_poses(joint: JointFrame, contacts: list[tuple[np.ndarray, np.ndarray, tuple[float, float]]]
                ) -> list[PressPose]:
    """Shelf lifts of a hinged part (after every palm and fingertip press): the fingers bent square under the
    surface at each contact (the shelf's top facing the push), pointing from the contact towards the hinge axis,
    the palm on the far side of the contact from the hinge; it slides in along the bent fingers. A door that lies
    open on its stop with its handle underneath (an oven's) is lifted shut by the edge beyond the handle, where no
    palm fits under it."""
    rot_t = joint.link[:3, :3].T
    axis = rot_t @ joint.axis
    hinge = rot_t @ (joint.point - joint.link[:3, 3])
    out = []
    for surface, m, shift in contacts:
        inward = hinge - surface
        inward -= np.dot(inward, axis) * axis + np.dot(inward, m) * m
        if np.linalg.norm(inward) < 1e-6:
            continue
        inward /= np.linalg.norm(inward)
        rot = palm_rotation(-m, inward)  # the palm's knuckle end against the push, bent fingers towards the hinge
        off = np.eye(4)
        off[:3, :3] = rot
        off[:3, 3] = surface - CONTACT_GAP_M * m - rot @ SHELF_CONTACT
        for follow in SHELF_FOLLOWS:
            out.append(PressPose(off, -inward, site="shelf", fingers="bent towards the hinge",
                                 back="along the bent fingers", shift_m=shift, follow=follow, q_ref=joint.q,
                                 contact=SHELF_CONTACT.copy(), hand=dict(SHELF_HAND)))
    return out


def _clear(palm: sapien.Pose, centres: np.ndarray, radii: np.ndarray, shapes: list[PosedShape],
           margin_m: float) -> bool:
    """Whether the hand's spheres (palm frame) at ``palm`` stay ``margin_m`` off every shape and the table."""
    m = palm.to_transformation_matrix()
    world = centres @ m[:3, :3].T + m[:3, 3]
    if np.any(world[:, 2] - radii < margin_m):
        return False
    return all(np.all(shape.signed_distance(world) - radii >= margin_m) for shape in shapes)


class PressPrimitives(HandlePrimitives):
    """The press primitives of one episode; ``hand_cover`` gives the open hand's sphere cover (palm frame) that
    the arm's collision model carries while it brings the hand to the part."""

    def __init__(self, motion, hand_cover: Callable[..., tuple[np.ndarray, np.ndarray]], config=None):
        super().__init__(motion, config, hand_cover)
        self._goals: dict[tuple[str, float], float] = {}
        """The goal each press pose was chosen for (part, direction)."""

    def run(self, prim: str, stage) -> Iterator[np.ndarray]:
        if prim not in ("approach_press", "press"):
            raise ExecutionError(f"no press primitive {prim!r}; primitives: approach_press, press",
                                 cause="unsupported")
        return getattr(self, prim)(stage)

    def _sign(self, stage) -> float:
        """+1 when ``stage`` (or, for a reach, the stage that moves the joint after it) opens the joint, else -1."""
        spec = self.motion.env.task_spec
        if stage.skill not in JOINT_SKILLS:
            stage = next((s for s in spec.stages if s.target == stage.target and s.skill in JOINT_SKILLS),
                         stage)
        if stage.skill in ("open", "close"):
            return 1.0 if stage.skill == "open" else -1.0
        conds = [c for c in (*(stage.success or ()), *spec.success.conditions)
                 if c.type == "joint_open" and c.object == stage.target]
        return -1.0 if conds and all(c.negate for c in conds) else 1.0

    def _press_goal(self, stage, sign: float, stay: bool = True) -> float:
        """Where the press takes the joint: the task's closed or open fraction (a margin past it). A lid opened for
        later stages is pushed on past its balance point (:meth:`_stays_open`), or it falls shut behind the hand."""
        u, name = self.motion.env, stage.target
        if sign < 0:
            return closing_goal(u, name, PRESS_CLOSE_FRACTION)
        goal = opening_goal(u, name)
        return self._stays_open(name, goal) if stay and self._hand_leaves(stage) else goal

    def _stays_open(self, name: str, goal: float) -> float:
        """``goal``, or where gravity no longer pulls the part back towards closed (+ :data:`STAY_MARGIN_RAD`,
        within the limits) when it does at ``goal`` (a bin's lid); ``goal`` when no such place is in range. Opening
        turns the joint towards its upper limit, as everywhere in the press."""
        u = self.motion.env
        joint = read_joint(u, name)
        if joint.prismatic or self._gravity(name, joint, np.array([goal]), 1.0)[0] >= 0:
            return goal
        end = float(u.articulations[name].get_qlimits()[0, u.joint_index(name), 1]) - 0.02
        qs = np.arange(goal, end, ARC_CHECK_RAD)
        holds = np.flatnonzero(self._gravity(name, joint, qs, 1.0) >= 0) if len(qs) else []
        if not len(holds):
            log.info("the %r part falls back from %.2f and has no balance point before its limit", name, goal)
            return goal
        return min(float(qs[holds[0]]) + STAY_MARGIN_RAD, end)

    def _gravity(self, name: str, joint: JointFrame, qs: np.ndarray, sign: float) -> np.ndarray:
        """[len(qs)] gravity's torque about the hinge on the moving part at joint positions ``qs``, positive
        where it turns the part towards ``sign`` (per unit mass: the lever arm of its centre of mass)."""
        body = px_bodies(self.motion.env.handle_link(name))[0]
        com = np.asarray(body.cmass_local_pose.p, dtype=np.float64)
        return np.array([sign * float(np.dot(joint.axis, np.cross(joint.point_at(com, q) - joint.point,
                                                                  [0.0, 0.0, -1.0]))) for q in qs])

    def _beyond(self, name: str, goal: float, sign: float) -> float:
        """The furthest joint position the press commands: a little past ``goal`` (within the limits)."""
        u = self.motion.env
        lo, hi = u.articulations[name].get_qlimits()[0, u.joint_index(name)].tolist()
        return float(np.clip(goal + sign * OVERSHOOT, lo, hi))

    def approach_press(self, stage) -> Iterator[np.ndarray]:
        ex, name = self.motion, stage.target
        u = ex.env
        joint = read_joint(u, name)
        sign = self._sign(stage)
        covers: dict[str, tuple[np.ndarray, np.ndarray]] = {}

        def search() -> tuple | None:
            goal = self._press_goal(stage, sign)
            chosen = self._find_press(stage, joint, sign, goal, covers)
            plain = self._press_goal(stage, sign, stay=False)
            if chosen is None and plain != goal:
                log.info("%r: no press reaches %.2f, where it would stay open; pressing to %.2f", name, goal, plain)
                goal = plain
                chosen = self._find_press(stage, joint, sign, goal, covers)
            return None if chosen is None else (*chosen, goal)

        found = self._clear_of_others(name, search)
        if found is None:
            raise ExecutionError(f"no press pose on {name!r}'s moving part that the arm can reach and follow along "
                                 f"its path", cause="no_ik")
        pose, q_pre, q0, pre, goal = found
        log.info("%r: %s", name, pose)
        self.grasp, self.target, self.hooked = pose, name, False
        self._goals[name, sign] = goal
        self._obstacles(self._part_boxes(name))
        ex.collision.cover_hand(*covers[pose.site])
        try:
            path = ex.plan_arm(q_pre, hand=q0)
        except ExecutionError as exc:  # the hand starts too close to something: plan the arm alone
            log.debug("no path with the hand covered (%s): planning the arm alone", exc)
            path = None
        finally:
            ex.collision.cover_hand(None)
        if path is None:
            yield from ex.move_arm(q_pre, hand=q0)
        else:
            yield from path
        back = joint.link[:3, :3] @ pose.normal_local
        yield from ex.cartesian(-pre * back, self.config.insert_m_per_step)
        yield from ex.settle()

    def _find_press(self, stage, joint: JointFrame, sign: float, goal: float,
                    covers: dict[str, tuple[np.ndarray, np.ndarray]]) -> tuple | None:
        """The first press pose (with its pre-pose joints, hand joints and pre-distance) whose open hand clears the
        part and the table, whose pre-pose the arm reaches, and whose path the arm follows to ``goal``'s stop."""
        ex, name = self.motion, stage.target
        u = ex.env
        stop = self._handover(name, joint, sign, goal)
        fixed = self._fixed_shapes(name)
        moving = self._shape(name).posed(joint.link)
        around = self._part_boxes(name)
        # a lever turned back to off: the fingertips slid off it short of shut (stalled at 0.15-0.17 rad in 8 of 8
        # dev seeds of a faucet and a valve), the bent fingers' shelf carried it home (13 of 13)
        back = sign < 0 and any(s.skill == "turn" and s.target == name for s in u.task_spec.stages)
        poke = any(s.skill == "press" and s.target == name for s in u.task_spec.stages)
        for pose in press_poses(joint, self._shape(name), handle_local(u, name), sign, shelf_first=back,
                                poke_first=poke):
            touch = pose.palm_at(joint, joint.q)
            if pose.site not in covers:
                covers[pose.site] = self.hand_cover(pose.hand)
            centres, radii = covers[pose.site]
            if not _clear(touch, centres, radii, [moving], -HAND_CLEAR_M):
                log.debug("%s: the hand would touch the part elsewhere", pose)
                continue
            if not all(_clear(p, centres, radii, fixed, HAND_CLEAR_M) for p in [touch, *self._arc(pose, joint, stop)]):
                log.debug("%s: the hand would hit the fixed part or the table", pose)
                continue
            q0 = ex.with_hand(ex.target(), pose.hand)
            q_pre = q_in = None
            for pre in PRE_M:  # a pre-pose the arm reaches with the open hand clear, and moves straight in from
                self._obstacles(around)  # the pre-pose: the open hand clear of the whole part
                ex.collision.cover_hand(centres, radii)
                try:
                    q_pre = ex.ik.solve(pose.palm_at(joint, joint.q, pre), q0, restarts=20, valid=ex.collision.is_free)
                finally:
                    ex.collision.cover_hand(None)
                if q_pre is None:
                    continue
                self._obstacles(self._boxes(name, moving=True, inflate_m=0.0))  # then the arm alone
                n = int(np.ceil(pre / INSERT_STEP_M))
                q_in = self._chain([pose.palm_at(joint, joint.q, pre * (1 - k / n)) for k in range(1, n + 1)], q_pre,
                                   CHAIN_RESTARTS)
                if q_in is not None:
                    break
            if q_in is None:
                log.debug("%s: %s", pose, "pre-pose unreachable" if q_pre is None else "no straight motion in")
                continue
            if self._chain(self._arc(pose, joint, self._beyond(name, stop, sign)), q_in, CHAIN_RESTARTS) is None:
                log.debug("%s: arm cannot follow the path", pose)
                continue
            return pose, q_pre, q0, pre
        return None

    def press(self, stage) -> Iterator[np.ndarray]:
        """Push the part along its path to the stage's goal with the open hand."""
        name = stage.target
        sign = self._sign(stage)
        if self.grasp is None or self.target != name or not isinstance(self.grasp, PressPose):
            yield from self.approach_press(stage)
        joint = read_joint(self.motion.env, name)
        lead = None
        if not joint.prismatic:  # the palm pushes PRESS_LEAD_M into the part, whatever the contact's radius
            touch = self.grasp.palm_at(joint, joint.q).to_transformation_matrix()
            point = touch[:3, :3] @ self.grasp.contact + touch[:3, 3] - joint.point
            radius = float(np.linalg.norm(point - np.dot(point, joint.axis) * joint.axis))
            lead = max(self.config.lead_rad, PRESS_LEAD_M / max(radius, 1e-3))
        goal = self._goals.get((name, sign))
        goal = self._press_goal(stage, sign) if goal is None else goal
        stop = self._handover(name, joint, sign, goal)
        yield from self._move_joint(stage, stop, sign, hand=self.grasp.hand, lead=lead)
        if stop == goal:
            if self._hand_leaves(stage):  # off the part first: an arm planned from a hand pressed on a door snags it
                yield from self._retreat(name)
            return
        yield from self._retreat(name)
        ex = self.motion
        for _ in range(FALL_STEPS):  # gravity carries the part on; the hand stays where it let go
            if sign * (float(ex.env.joint_qpos(name)[0]) - goal) >= 0:
                return
            yield ex.emit(ex.target())
        raise ExecutionError(f"the joint of {name!r} stopped at {float(ex.env.joint_qpos(name)[0]):.3f} after the "
                             f"hand let it go at {stop:.3f} (goal {goal:.3f})", cause="target_not_reached")

    def _retreat(self, name: str) -> Iterator[np.ndarray]:
        """Out of the part's way: :data:`RETREAT_M` back against the push, and as much up."""
        ex = self.motion
        joint = read_joint(ex.env, name)
        touch = self.grasp.palm_at(joint, joint.q).to_transformation_matrix()
        away = -RETREAT_M * touch[:3, :3] @ np.array([0.0, -1.0, 0.0]) + np.array([0.0, 0.0, RETREAT_M])
        try:
            yield from ex.cartesian(away, self.config.insert_m_per_step)
        except ExecutionError as exc:
            log.debug("no retreat from %r (%s)", name, exc)

    def _hand_leaves(self, stage) -> bool:
        """Whether a later stage acts on something other than ``stage``'s part (the hand leaves it)."""
        later = [s.target for s in self.motion.env.task_spec.stages]
        return stage.target in later and later[::-1].index(stage.target) > 0

    def _handover(self, name: str, joint: JointFrame, sign: float, goal: float) -> float:
        """Where the press may stop: the joint position :data:`HANDOVER_MARGIN_RAD` past the point after which
        gravity turns the part the rest of the way to ``goal`` with at least :data:`HANDOVER_TORQUE_FRACTION` of
        its largest torque (a lid pushed back over upright falls shut), or ``goal`` when gravity never does (a door,
        a lever, a slide)."""
        if joint.prismatic:
            return goal
        qs = np.arange(joint.q, goal, sign * ARC_CHECK_RAD)
        if len(qs) == 0:
            return goal
        torque = self._gravity(name, joint, qs, sign)
        helps = torque >= max(HANDOVER_TORQUE_FRACTION * float(torque.max()), 1e-6)
        start = len(helps)
        while start > 0 and helps[start - 1]:
            start -= 1
        if start >= len(qs):
            return goal
        stop = float(qs[start] + sign * HANDOVER_MARGIN_RAD)
        return goal if sign * (stop - goal) >= 0 else stop


__all__ = ["CONTACT_GAP_M", "FINGER_CONTACT", "PALM_CONTACT", "PressPose", "PressPrimitives", "press_direction",
           "press_poses"]
