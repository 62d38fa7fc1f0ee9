"""The critic's physical checks: what GenDex measures itself on a scene, with arithmetic fixes where they exist.

Two entry points:

* :func:`check_scene_static` needs no simulator (milliseconds): reach, off_table, in_front, scale, joint_state,
  unsupported, the skills' and the structures' checks, and penetration estimated from bounding boxes.
* :func:`~generator.critic.physical_sim.check_scene` (:mod:`generator.critic.physical_sim`) builds the scene in
  SAPIEN and replaces the bounding-box penetration estimate with PhysX's own contacts, then lets the scene settle
  and measures what fell or still moves.

Each :class:`Violation` names its check, object, measured value and limit, and carries a suggested fix: directives
(:mod:`generator.critic.directives`) where arithmetic can fix it, or a joint-state edit (``joint_fix``, applied with
:func:`apply_joint_fix`) for a joint that starts in the state the task should produce. Several violations of one
object may carry the same directive (an object both off the table and out of reach gets one combined move);
:meth:`PhysicalReport.directives` lists each distinct directive once, so applying that list applies every fix once.

How each check is measured (the thresholds are the module constants below):

``penetration``
    Simulator: after reset one physics step is taken and PhysX's contact list read; a contact point's
    ``separation`` < -PENETRATION_TOL_M between two objects, an object and the table, or an object and a robot
    link is a penetration (contacts inside one articulation, robot-robot and robot-table are ignored). PhysX
    reports the depth along the contact normal per convex-hull pair, which for deep overlaps understates the true
    overlap, so the fix is computed from the bodies' collision-shape AABBs instead: the smaller movable object is
    moved in xy until the AABBs no longer overlap in x or y (+ PENETRATION_FIX_MARGIN_M + both objects'
    randomization half-ranges), along the line between the two AABB centres or, where that ends off the table, out
    of reach, on a third object or in front of an articulated object a stage works, along the shortest table axis
    that does not (:mod:`generator.critic.layout`); a penetration of the table is fixed by raising the object.
    Static: the same on the catalog bounding boxes placed by the spec; an object whose footprint
    lies inside a container's footprint and that is above the table is *not* counted (it may rest on the
    container's floor; only the simulator can tell). Randomization is off for the measurement (nominal poses).
``unsupported`` (static)
    An object whose lowest point is more than SUPPORT_TOL_M above the table and whose footprint centre is not over
    another object whose vertical extent reaches up to it (within SUPPORT_TOL_M). Fix: ``move_z`` down onto the
    table, onto the top of the non-container object below it, or to CONTAINER_FLOOR_M x scale above the bottom of a
    container below it.
``floating`` (simulator)
    After ``settle_steps`` control steps with the robot holding still (zero ``pd_joint_delta_pos`` actions), a
    movable object that sank more than FALL_TOL_M or still moves faster than MOVING_TOL_MPS. Objects off the table
    are left to ``off_table``. Fix: the ``unsupported`` fix if there is one, else ``move_z`` by minus the measured
    drop (nothing for an object that only keeps moving).
``out_of_reach`` (static)
    Horizontal distance from the robot base to the nearest point of the object's footprint, plus the object's xy
    randomization half-range (worst case), above REACH_MAX_M; or distance from the base to the footprint centre,
    minus that half-range, below REACH_MIN_M. Only objects the task refers to (stage targets, success-condition
    objects and targets) are checked; a scene that refers to none has all its objects checked. Fix: move along the
    line to the base until the distance is REACH_MARGIN_M inside the limit.
``off_table`` (static)
    Footprint centre (of the rotated bounding box) outside the table top. Fix: move so the whole footprint is on the
    table, OFF_TABLE_MARGIN_M from the edge (centred when it is larger than the table), combined with the reach fix.
``in_front`` (static)
    An object that no stage or condition names (clutter) whose footprint, widened by its randomization, reaches into
    the front zone (:func:`~generator.critic.layout.front_zone`) of an articulated object a stage works: a door
    pressed shut shoves it against the body and stalls. Fix: moved out of the zone, as a penetration fix moves.
``scale``
    (a) :func:`check_raw_scales` on a raw task mapping: a scale outside SCALE_RANGE (such a spec cannot be parsed);
    fix: the factor back into range. (b) A graspable, rigid object that the task grasps (a stage targeting it has a
    skill of :data:`GRASP_SKILLS`, or a ``lifted`` condition names it, or it is the object of an ``inside``
    condition) whose smallest horizontal width as placed exceeds GRASP_MAX_WIDTH_M, or whose largest
    extent is below GRASP_MIN_SIZE_M; fix: the scale factor that brings it inside. (c) A scale outside
    REALISTIC_SCALE_RANGE is reported with severity ``warning`` (a catalog asset at 0.3x or 2x is no longer the
    object it depicts); warnings do not make a report fail.
``joint_state`` (static)
    An articulated object whose initial joint state contradicts the first stage that targets it with skill
    ``open`` or ``close``: "open" while the joint starts at least JOINT_OPEN_FRACTION open, "close" while it starts
    less than that open. With no such stage, a ``joint_open`` success condition on the object means "open" (every
    one negated: "close", a turn off). A joint a ``joint_at`` condition sets part way must not start within its
    ``max_error`` of the fraction (fix: the end of its range further from it). The
    fraction is (q - closed) / (open - closed) of the joint the conditions name, else the asset's main joint.
    Fix: ``joint_fix`` = {object, joint, value} setting the joint to its closed (resp. open) value; the directive
    grammar has no joint edit.
``handover``, ``insert``, ``wipe``, ``hang``, ``pour``, ``flip`` (static)
    What a skill needs of the scene: :mod:`generator.critic.skill_checks` (an object to hand over starts clear of
    its hand-over zone, a peg of its holder, a sponge of its spill). No check measures the pieces laid in a vessel to
    pour (:mod:`gendex_envs.pouring`): they move with it.
``structure_room`` (static)
    A scene's fixed structures leave the arm room: none near the robot base, in the arm's room over the table or on
    an object's start region (:mod:`generator.critic.room`). No directive moves a structure.
"""

from __future__ import annotations

import json
import logging
import math
import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal, get_args

import numpy as np

from gendex_envs.assets.catalog import AssetRecord, get_asset, lowest_point_z
from gendex_envs.conditions import CONDITION_DEFAULTS
from gendex_envs.placement import in_drawer
from gendex_envs.pouring import spec_fills
from gendex_envs.spec import SCALE_RANGE, ObjectSpec, TaskSpec
from generator.critic.directives import Directive
from generator.critic.layout import Room, choose_move, front_zone, min_width_xy
from generator.critic.room import structure_room
from generator.critic.skill_checks import skill_checks

log = logging.getLogger(__name__)

CheckId = Literal["penetration", "floating", "unsupported", "out_of_reach", "off_table", "in_front", "scale",
                  "joint_state", "handover", "insert", "wipe", "hang", "pour", "flip", "structure_room"]
CHECKS: tuple[str, ...] = get_args(CheckId)

# ----------------------------------------------------------------------------------------------- thresholds
PENETRATION_TOL_M = 0.003
"""Deepest tolerated interpenetration at reset (m). Objects placed by the spec rest at separation ~0 (measured
0.0 on the reference tasks); an apple placed at the centre of the bowl sits 6 mm into its floor."""
SUPPORT_TOL_M = 0.005
"""An object's lowest point may be this far above the table, or above / below the top of what it stands on (m)."""
CONTAINER_FLOOR_M = 0.01
"""Guessed floor thickness of a container at scale 1 (m): an unsupported object above a container is lowered to this
clearance above the container's bottom (the bowl's floor is ~7 mm thick)."""
FALL_TOL_M = 0.01
"""A movable object that sank more than this while settling was floating (m)."""
MOVING_TOL_MPS = 0.05
"""A movable object still faster than this after settling is not at rest (m/s)."""
SETTLE_STEPS = 20
"""Control steps (20 Hz: 1 s) the scene settles for; an object released 0.3 m up lands in 0.25 s."""

REACH_MAX_M = 1.25
"""Farthest horizontal distance (m) from the robot base to the nearest point of an object's footprint.

The issue's "> 0.8 m from the base" comes from the seed paper, whose base stood at x = -0.5 in front of a smaller
workspace; it does not describe this robot. GenDex's UR10e stands at x = -0.8, and its published reach is 1.30 m
(base axis to wrist flange) plus ~0.2 m of ShadowHand (wrist to fingertips). Reaching down to a table that is level
with the base, with the palm above or beside the object, costs part of that, so 1.25 m to the object's nearest point
is kept as the limit. The reference tasks place objects 1.0-1.4 m from the base; their nearest points lie within
0.89-1.16 m even with their randomization added (the cabinet, 1.4 m away at its centre, has its front 1.13 m away)."""
REACH_MIN_M = 0.35
"""Closest horizontal distance (m) from the base to an object's footprint centre: nearer than this the hand cannot
fold back down to it (the shoulder and elbow take up the space around the base axis)."""
REACH_MARGIN_M = 0.05
"""How far inside a reach limit a reach fix puts the object (m)."""
OFF_TABLE_MARGIN_M = 0.02
"""Distance from the table edge that an off_table fix leaves (m)."""

GRASP_MAX_WIDTH_M = 0.12
"""Widest object (smallest horizontal width as placed, m) the ShadowHand closes around: its thumb-to-finger span is
~0.15 m fully spread, and a stable power / top grasp needs the fingers to wrap past the object's middle."""
GRASP_MIN_SIZE_M = 0.015
"""Smallest graspable object (largest extent, m): below this the fingertips (~2 cm wide) cannot pinch it."""
GRASP_FIX_FILL = 0.9
"""A grasp-size fix scales the object to this fraction of GRASP_MAX_WIDTH_M (or 1/this of GRASP_MIN_SIZE_M)."""
REALISTIC_SCALE_RANGE: tuple[float, float] = (0.5, 1.5)
"""Scales outside this range are reported as warnings: catalog sizes are real-world sizes, and real objects of one
kind vary about +/-50 %; a 2x apple (15 cm) or a 0.3x bottle (7 cm) no longer looks like what it is."""
JOINT_OPEN_FRACTION = 0.5
"""A joint at least this fraction of the way from closed to open counts as open (joint_state check)."""

GRASP_SKILLS = frozenset({"grasp", "lift"})
"""Skills whose target is the object in the hand, so it must fit the hand (the ``scale`` check); a carry's target is
the destination."""
JOINT_SKILLS = {"open": "open", "close": "close"}
"""Skills that state what an articulated target's joint should do (the ``joint_state`` check)."""


# ------------------------------------------------------------------------------------------------ records
@dataclass(frozen=True)
class Violation:
    """One failed check."""

    check: CheckId
    """One of CHECKS."""
    object: str | None
    """The object at fault (None for scene-level problems)."""
    message: str
    """One readable sentence, fit to feed back to the model."""
    measured: float | None = None
    """The measured value (m, m/s, scale or fraction; see the message)."""
    limit: float | None = None
    """The threshold it broke."""
    fix: tuple[Directive, ...] = ()
    """Suggested directives that fix it by arithmetic (empty where none exists)."""
    joint_fix: dict[str, Any] | None = None
    """joint_state violations: {"object", "joint", "value"}, for :func:`apply_joint_fix`."""
    severity: Literal["error", "warning"] = "error"
    """Warnings are reported but do not make the report fail."""
    other: str | None = None
    """The second party: of a penetration an object, ``table`` or ``robot:<link>``; of in_front, the articulated one."""

    def to_dict(self) -> dict[str, Any]:
        return {"check": self.check, "object": self.object, "message": self.message,
                "measured": rounded(self.measured), "limit": rounded(self.limit), "fix": [str(d) for d in self.fix],
                "joint_fix": self.joint_fix, "severity": self.severity, "other": self.other}


@dataclass
class PhysicalReport:
    """Violations and per-check measurements of one scene; JSON-able via :meth:`to_dict`."""

    task: str
    mode: Literal["static", "sim"]
    violations: list[Violation] = field(default_factory=list)
    measurements: dict[str, dict[str, Any]] = field(default_factory=dict)
    """check id -> object name -> measured quantities (plus ``_method`` entries saying how)."""
    seconds: float = 0.0

    @property
    def ok(self) -> bool:
        """No error-severity violation."""
        return not any(v.severity == "error" for v in self.violations)

    @property
    def errors(self) -> list[Violation]:
        return [v for v in self.violations if v.severity == "error"]

    def by_check(self, check: str) -> list[Violation]:
        return [v for v in self.violations if v.check == check]

    def directives(self, include_warnings: bool = False) -> list[Directive]:
        """Each distinct suggested directive once, in violation order."""
        out: list[Directive] = []
        for v in self.violations:
            if v.severity == "warning" and not include_warnings:
                continue
            out += [d for d in v.fix if d not in out]
        return out

    def joint_fixes(self) -> list[dict[str, Any]]:
        return [v.joint_fix for v in self.violations if v.joint_fix is not None]

    def to_dict(self) -> dict[str, Any]:
        return {"task": self.task, "mode": self.mode, "ok": self.ok, "seconds": round(self.seconds, 3),
                "violations": [v.to_dict() for v in self.violations], "measurements": self.measurements}

    def to_json(self, **kwargs) -> str:
        return json.dumps(self.to_dict(), **kwargs)

    def summary(self) -> str:
        """One line per violation with its suggested fix; 'no physical problems found' when there is none."""
        if not self.violations:
            return "no physical problems found"
        lines = []
        for v in self.violations:
            fix = "; fix: " + " | ".join(str(d) for d in v.fix) if v.fix else ""
            if v.joint_fix:
                fix = f"; fix: set {v.joint_fix['object']}.joint_state.{v.joint_fix['joint']} = {v.joint_fix['value']}"
            lines.append(f"[{v.severity} {v.check}] {v.message}{fix}")
        return "\n".join(lines)


def rounded(x: float | None, nd: int = 4) -> float | None:
    return None if x is None else round(float(x), nd)


# --------------------------------------------------------------------------------------------- geometry
def _rotation(q_wxyz: Iterable[float]) -> np.ndarray:
    w, x, y, z = np.asarray(list(q_wxyz), dtype=np.float64) / np.linalg.norm(list(q_wxyz))
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


@dataclass(frozen=True)
class Placed:
    """An object as the spec places it: catalog record and world corners of its rotated, scaled bounding box."""

    spec: ObjectSpec
    record: AssetRecord
    corners: np.ndarray  # [8, 3] world

    @property
    def lo(self) -> np.ndarray:
        return self.corners.min(axis=0)

    @property
    def hi(self) -> np.ndarray:
        return self.corners.max(axis=0)

    @property
    def centre_xy(self) -> np.ndarray:
        return (self.lo[:2] + self.hi[:2]) / 2

    @property
    def area(self) -> float:
        d = self.hi[:2] - self.lo[:2]
        return float(d[0] * d[1])

    @property
    def is_container(self) -> bool:
        return "container" in self.record.tags


def _frame(obj: ObjectSpec) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(scaled local box lo, hi, world origin) of an object as the spec places it."""
    rec = get_asset(obj.asset)
    lo, hi = np.asarray(rec.bbox_min_m) * obj.scale, np.asarray(rec.bbox_max_m) * obj.scale
    return lo, hi, np.array([obj.pos_m[0], obj.pos_m[1], obj.pos_m[2] - lowest_point_z(rec, obj.scale, obj.quat_wxyz)])


def _place(obj: ObjectSpec) -> Placed:
    lo, hi, origin = _frame(obj)
    local = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    return Placed(obj, get_asset(obj.asset), local @ _rotation(obj.quat_wxyz).T + origin)


def _footprint_inside(inner_lo, inner_hi, outer_lo, outer_hi) -> bool:
    return bool(np.all(inner_lo[:2] >= outer_lo[:2] - 1e-9) and np.all(inner_hi[:2] <= outer_hi[:2] + 1e-9))


def moves(obj: str, dxy: Iterable[float]) -> tuple[Directive, ...]:
    """move_x / move_y directives for an xy translation, rounded to mm away from zero (components < 0.5 mm dropped)."""
    out = []
    for axis, d in zip("xy", dxy, strict=True):
        if abs(d) >= 5e-4:
            out.append(Directive.move(obj, axis, math.copysign(math.ceil(abs(d) * 1000) / 1000, d)))
    return tuple(out)


def _scale_factor(scale: float, target: float) -> float:
    """Factor (4 decimals) that takes ``scale`` to about ``target``, rounded so the result stays in SCALE_RANGE."""
    lo, hi = SCALE_RANGE
    target = min(max(target, lo), hi)
    f = target / scale
    f = math.floor(f * 1e4) / 1e4 if f < 1 else math.ceil(f * 1e4) / 1e4
    while scale * f > hi:
        f -= 1e-4
    while scale * f < lo:
        f += 1e-4
    return round(f, 4)


# ----------------------------------------------------------------------------------------------- checks
def _task_objects(spec: TaskSpec) -> set[str]:
    names = {s.target for s in spec.stages if s.target}
    for c in spec.success.conditions:
        names.add(c.object)
        if c.target and c.target != "goal":
            names.add(c.target)
    return names & {o.name for o in spec.objects} or {o.name for o in spec.objects}


def _grasped(spec: TaskSpec, name: str) -> bool:
    if any(s.target == name and s.skill in GRASP_SKILLS for s in spec.stages):
        return True
    return any(c.object == name and c.type in ("lifted", "inside") for c in spec.success.conditions)


def _position_fixes(spec: TaskSpec, placed: dict[str, Placed], meas_reach: dict, meas_table: dict,
                    violations: list[Violation]) -> None:
    bx, by = spec.robot.base_pos_m[:2]
    base = np.array([bx, by])
    sx, sy = spec.table.size_m
    checked = _task_objects(spec)
    for name, p in placed.items():
        o = p.spec
        jitter = math.hypot(*o.randomize.xy_m)
        lo, hi = p.lo[:2], p.hi[:2]
        gap = np.maximum(np.maximum(lo - base, base - hi), 0.0)
        near = float(np.linalg.norm(gap))
        centre = p.centre_xy
        d_centre = float(np.linalg.norm(centre - base))
        meas_reach[name] = {"nearest_m": rounded(near), "centre_m": rounded(d_centre), "randomize_m": rounded(jitter),
                            "checked": name in checked}
        on_table = abs(centre[0]) <= sx / 2 and abs(centre[1]) <= sy / 2
        meas_table[name] = {"centre_xy_m": [rounded(centre[0]), rounded(centre[1])], "on_table": bool(on_table)}
        too_far = name in checked and near + jitter > REACH_MAX_M
        too_close = name in checked and d_centre - jitter < REACH_MIN_M
        if on_table and not too_far and not too_close:
            continue
        # one combined target for the footprint centre: on the table, then within reach
        half = (hi - lo) / 2
        target = centre.copy()
        if not on_table:
            for i, size in enumerate((sx, sy)):
                room = size / 2 - half[i] - OFF_TABLE_MARGIN_M
                target[i] = 0.0 if room <= 0 else min(max(target[i], -room), room)
        rel = target - base
        dist = float(np.linalg.norm(rel))
        u = rel / dist if dist > 1e-6 else np.array([1.0, 0.0])
        t_lo, t_hi = lo + (target - centre), hi + (target - centre)
        near_t = float(np.linalg.norm(np.maximum(np.maximum(t_lo - base, base - t_hi), 0.0)))
        if name in checked and near_t + jitter > REACH_MAX_M:
            target = target - u * (near_t + jitter - (REACH_MAX_M - REACH_MARGIN_M))
        if name in checked and float(np.linalg.norm(target - base)) - jitter < REACH_MIN_M:
            target = base + u * (REACH_MIN_M + REACH_MARGIN_M + jitter)
        fix = moves(name, target - centre)
        if not on_table:
            violations.append(Violation(
                "off_table", name, f"{name!r} has its footprint centre at ({centre[0]:.3f}, {centre[1]:.3f}) m, "
                f"outside the {sx} x {sy} m table top (|x| <= {sx / 2}, |y| <= {sy / 2})",
                measured=float(max(abs(centre[0]) - sx / 2, abs(centre[1]) - sy / 2)), limit=0.0, fix=fix))
        if too_far:
            violations.append(Violation(
                "out_of_reach", name, f"{name!r} is out of reach: its nearest point is {near:.3f} m from the robot "
                f"base (+{jitter:.3f} m randomization), beyond the {REACH_MAX_M} m the hand reaches",
                measured=near + jitter, limit=REACH_MAX_M, fix=fix))
        if too_close:
            violations.append(Violation(
                "out_of_reach", name, f"{name!r} is too close to the robot base ({d_centre:.3f} m to its centre, "
                f"-{jitter:.3f} m randomization); the hand cannot fold back nearer than {REACH_MIN_M} m",
                measured=d_centre - jitter, limit=REACH_MIN_M, fix=fix))


def _support(p: Placed, placed: dict[str, Placed]) -> tuple[bool, float]:
    """(supported, clearance it could rest at): resting on the table or over another object reaching up to it."""
    bottom = float(p.lo[2])
    if bottom <= SUPPORT_TOL_M:
        return True, 0.0
    c = p.centre_xy
    rest = 0.0
    for other in placed.values():
        if other is p:
            continue
        if other.record.articulated and in_drawer(p.spec, other.spec, other.record):
            return True, bottom  # in a slid-out drawer, whose bin the chest's closed box leaves out
        if not (other.lo[0] <= c[0] <= other.hi[0] and other.lo[1] <= c[1] <= other.hi[1]):
            continue
        if other.lo[2] - SUPPORT_TOL_M <= bottom <= other.hi[2] + SUPPORT_TOL_M:
            return True, bottom
        if other.hi[2] < bottom:  # below it: where it would land
            land = (float(other.lo[2]) + CONTAINER_FLOOR_M * other.spec.scale if other.is_container
                    else float(other.hi[2]))
            rest = max(rest, land)
    return False, rest


def _unsupported(placed: dict[str, Placed], meas: dict, violations: list[Violation]) -> dict[str, tuple]:
    fixes: dict[str, tuple[Directive, ...]] = {}
    for name, p in placed.items():
        ok, rest = _support(p, placed)
        bottom = float(p.lo[2])
        meas[name] = {"clearance_m": rounded(bottom), "supported": ok}
        if ok:
            continue
        drop = bottom - rest
        fix = (Directive.move(name, "z", -math.floor(drop * 1000) / 1000),) if drop >= 1e-3 else ()
        fixes[name] = fix
        where = "the table" if rest == 0.0 else f"what is below it (top at {rest:.3f} m)"
        violations.append(Violation(
            "unsupported", name, f"{name!r} floats {bottom:.3f} m above the table with nothing under it; it would "
            f"fall {drop:.3f} m onto {where}", measured=bottom, limit=SUPPORT_TOL_M, fix=fix))
    return fixes


def _overlaps(spec: TaskSpec, placed: dict[str, Placed], meas: dict, violations: list[Violation]) -> None:
    names = list(placed)
    meas["_method"] = "catalog bounding boxes placed by the spec"
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            pa, pb = placed[a], placed[b]
            depth = float(np.min(np.minimum(pa.hi, pb.hi) - np.maximum(pa.lo, pb.lo)))
            if depth <= PENETRATION_TOL_M:
                continue
            inside = [(x, y) for x, y in ((pa, pb), (pb, pa))
                      if y.is_container and _footprint_inside(x.lo, x.hi, y.lo, y.hi) and x.lo[2] > SUPPORT_TOL_M]
            if inside:
                meas.setdefault(inside[0][0].spec.name, {})["inside_container"] = inside[0][1].spec.name
                continue
            mover, other = pick_mover(pa, pb)
            fix = penetration_fix(spec, placed, mover, other, (mover.lo, mover.hi), (other.lo, other.hi))
            meas.setdefault(a, {})[b] = rounded(depth)
            violations.append(Violation(
                "penetration", mover.spec.name, f"{a!r} and {b!r} overlap by {depth:.3f} m (bounding boxes as placed)",
                measured=depth, limit=PENETRATION_TOL_M, fix=fix, other=other.spec.name))


def _clutter_in_front(spec: TaskSpec, placed: dict[str, Placed], meas: dict, violations: list[Violation]) -> None:
    named, worked = _task_objects(spec), {s.target for s in spec.stages if s.target}
    for owner, a in ((n, a) for n, a in placed.items() if a.record.articulated and n in worked):
        lo, hi, origin = _frame(a.spec)
        zone = front_zone(lo, hi, _rotation(a.spec.quat_wxyz), origin, a.spec.randomize.xy_m, a.spec.randomize.yaw_deg)
        for name, p in placed.items():
            j = np.asarray(p.spec.randomize.xy_m, dtype=float)
            depth = float(np.min(np.minimum(p.hi[:2] + j, zone[1]) - np.maximum(p.lo[:2] - j, zone[0])))
            if name in named or p.record.articulated or depth <= 0.0:
                continue
            d = choose_move(p.lo, p.hi, np.r_[zone[0], 0.0], np.r_[zone[1], 0.0], room_for(spec, placed, (name,)),
                            float(zone[:, 1].mean()), j, j)
            meas.setdefault(name, {})[owner] = rounded(depth)
            violations.append(Violation("in_front", name, f"{name!r}, which the task does not use, reaches {depth:.3f} "
                                        f"m (randomized) into the room in front of {owner!r} that its moving part "
                                        "sweeps", measured=depth, limit=0.0, fix=moves(name, d), other=owner))


def room_for(spec: TaskSpec, placed: dict[str, Placed], skip: Iterable[str]) -> Room:
    """Where a penetration fix may put an object (:class:`~generator.critic.layout.Room`): the table, the reach
    limits with REACH_MARGIN_M to spare, the objects not in ``skip``, and the front zones of the articulated objects
    that a stage targets."""
    worked = {s.target for s in spec.stages if s.target}
    obstacles, zones = [], []
    for name, p in placed.items():
        if name in skip:
            continue
        j = np.asarray(p.spec.randomize.xy_m, dtype=float)
        obstacles.append((np.r_[p.lo[:2] - j, p.lo[2]], np.r_[p.hi[:2] + j, p.hi[2]]))
        if p.record.articulated and name in worked:
            lo, hi, origin = _frame(p.spec)
            zones.append(front_zone(lo, hi, _rotation(p.spec.quat_wxyz), origin, j, p.spec.randomize.yaw_deg))
    return Room((spec.table.size_m[0] / 2, spec.table.size_m[1] / 2), tuple(spec.robot.base_pos_m[:2]),
                (REACH_MIN_M + REACH_MARGIN_M, REACH_MAX_M - REACH_MARGIN_M), tuple(obstacles), tuple(zones))


def penetration_fix(spec: TaskSpec, placed: dict[str, Placed], mover: Placed, other: Placed, mover_box: tuple,
                    other_box: tuple) -> tuple[Directive, ...]:
    """Directives moving ``mover`` (its 3-D box ``mover_box``) out of ``other`` (``other_box``), as measured by the
    caller (catalog boxes or the simulator's), into a spot :func:`room_for` admits where one is near."""
    room = room_for(spec, placed, (mover.spec.name, other.spec.name))
    (mlo, mhi), (olo, ohi) = mover_box, other_box
    d = choose_move(mlo, mhi, olo, ohi, room, float((olo[1] + ohi[1]) / 2), randomization_xy(mover, other),
                    mover.spec.randomize.xy_m)
    return moves(mover.spec.name, d)


def randomization_xy(*placed: Placed) -> np.ndarray:
    """Sum of the objects' xy randomization half-ranges, per axis."""
    return np.sum([p.spec.randomize.xy_m for p in placed], axis=0)


def pick_mover(pa: Placed, pb: Placed) -> tuple[Placed, Placed]:
    """(the one to move, the other): a movable one before a fixed one, then the smaller footprint."""
    key = [(p.spec.fixed, p.area) for p in (pa, pb)]
    return (pa, pb) if key[0] <= key[1] else (pb, pa)


def _scale_checks(spec: TaskSpec, placed: dict[str, Placed], meas: dict, violations: list[Violation]) -> None:
    rlo, rhi = REALISTIC_SCALE_RANGE
    for name, p in placed.items():
        o, rec = p.spec, p.record
        width = min_width_xy(p.corners)
        size = max(rec.size_m) * o.scale
        grasped = _grasped(spec, name) and "graspable" in rec.tags and not rec.articulated
        meas[name] = {"scale": o.scale, "min_width_m": rounded(width), "max_extent_m": rounded(size),
                      "grasped": grasped}
        if grasped and width > GRASP_MAX_WIDTH_M:
            f = _scale_factor(o.scale, o.scale * GRASP_MAX_WIDTH_M * GRASP_FIX_FILL / width)
            enough = width * f <= GRASP_MAX_WIDTH_M
            violations.append(Violation(
                "scale", name, f"{name!r} is too big for the ShadowHand to grasp: {width:.3f} m wide at scale "
                f"{o.scale:g} (at most {GRASP_MAX_WIDTH_M} m)" + ("" if enough else
                f"; even the smallest scale {SCALE_RANGE[0]} leaves it {width * f:.3f} m wide, use another asset"),
                measured=width, limit=GRASP_MAX_WIDTH_M, fix=(Directive.scale(name, f),) if f != 1 else ()))
        elif grasped and size < GRASP_MIN_SIZE_M:
            f = _scale_factor(o.scale, o.scale * GRASP_MIN_SIZE_M / GRASP_FIX_FILL / size)
            violations.append(Violation(
                "scale", name, f"{name!r} is too small to grasp: {size:.3f} m at scale {o.scale:g} (at least "
                f"{GRASP_MIN_SIZE_M} m)", measured=size, limit=GRASP_MIN_SIZE_M,
                fix=(Directive.scale(name, f),) if f != 1 else ()))
        if not rlo <= o.scale <= rhi:
            f = _scale_factor(o.scale, min(max(o.scale, rlo), rhi))
            violations.append(Violation(
                "scale", name, f"{name!r} at scale {o.scale:g} is {size:.2f} m across: far from the real size of a "
                f"{rec.category} (realistic scales {rlo}-{rhi})", measured=o.scale,
                limit=rlo if o.scale < rlo else rhi, fix=(Directive.scale(name, f),), severity="warning"))


def _joint_checks(spec: TaskSpec, placed: dict[str, Placed], meas: dict, violations: list[Violation]) -> None:
    for name, p in placed.items():
        rec = p.record
        if not rec.articulated or not rec.joints:
            continue
        intent, source = None, None
        for s in spec.stages:
            if s.target == name and s.skill in JOINT_SKILLS:
                intent, source = JOINT_SKILLS[s.skill], f"stage {s.name!r} (skill {s.skill!r})"
                break
        conds = [c for c in spec.success.conditions if c.object == name and c.type == "joint_open"]
        if intent is None and conds:  # a turn (or no stage): the success condition says which way
            shut = all(c.negate for c in conds)
            intent = "close" if shut else "open"
            source = f"the {'negated ' if shut else ''}joint_open success condition"
        joint_name = next((c.joint for c in conds if c.joint), None)
        try:
            joint = rec.joint(joint_name) if joint_name else rec.joints[0]
        except KeyError:
            joint = rec.joints[0]
        q = p.spec.joint_state.get(joint.name, joint.closed_qpos)
        span = joint.open_qpos - joint.closed_qpos
        frac = (q - joint.closed_qpos) / span if span else 0.0
        meas[name] = {"joint": joint.name, "qpos": rounded(q), "open_fraction": rounded(frac), "intent": intent}
        at = next((c for c in spec.success.conditions if c.object == name and c.type == "joint_at" and not c.negate),
                  None)
        if at is not None:  # set part way: it must not start there; the fix starts it at the end further away
            err = at.max_error if at.max_error is not None else CONDITION_DEFAULTS["max_error"]
            if abs(frac - at.fraction) <= err:
                far = joint.closed_qpos if at.fraction >= 0.5 else joint.open_qpos
                violations.append(Violation(
                    "joint_state", name, f"{name!r} starts {frac:.0%} open ({joint.name} = {q:g}), already within "
                    f"{err:.0%} of the {at.fraction:.0%} the joint_at success condition asks for", measured=frac,
                    limit=at.fraction, joint_fix={"object": name, "joint": joint.name, "value": far}))
            continue
        if intent == "open" and frac >= JOINT_OPEN_FRACTION:
            violations.append(Violation(
                "joint_state", name, f"{name!r} starts {frac:.0%} open ({joint.name} = {q:g}) but {source} "
                f"asks to open it", measured=frac, limit=JOINT_OPEN_FRACTION,
                joint_fix={"object": name, "joint": joint.name, "value": joint.closed_qpos}))
        elif intent == "close" and frac < JOINT_OPEN_FRACTION:
            violations.append(Violation(
                "joint_state", name, f"{name!r} starts closed ({frac:.0%} open, {joint.name} = {q:g}) but {source} "
                f"asks to close it", measured=frac, limit=JOINT_OPEN_FRACTION,
                joint_fix={"object": name, "joint": joint.name, "value": joint.open_qpos}))


def static_findings(spec: TaskSpec, overlap: bool) -> tuple[list[Violation], dict[str, dict], dict[str, Placed], dict]:
    pieces = {n for names in spec_fills(spec).values() for n in names}
    placed = {o.name: _place(o) for o in spec.objects if o.name not in pieces}
    violations: list[Violation] = []
    meas: dict[str, dict] = {c: {} for c in CHECKS}
    if overlap:
        _overlaps(spec, placed, meas["penetration"], violations)
    unsupported = _unsupported(placed, meas["unsupported"], violations)
    _position_fixes(spec, placed, meas["out_of_reach"], meas["off_table"], violations)
    _clutter_in_front(spec, placed, meas["in_front"], violations)
    _scale_checks(spec, placed, meas["scale"], violations)
    _joint_checks(spec, placed, meas["joint_state"], violations)
    skill_checks(spec, placed, meas, violations)  # what skills need (generator.critic.skill_checks)
    structure_room(spec, placed, meas["structure_room"], violations)  # room for the arm (generator.critic.room)
    return violations, meas, placed, unsupported


def check_scene_static(spec: TaskSpec) -> PhysicalReport:
    """The checks that need no simulator (module docstring): a quick pre-screen of a scene."""
    t0 = time.perf_counter()
    violations, meas, _, _ = static_findings(spec, overlap=True)
    meas["floating"]["_method"] = "not measured (needs the simulator)"
    report = PhysicalReport(spec.name, "static", ordered(violations), meas, time.perf_counter() - t0)
    log.info("static physical check of %s: %d violations", spec.name, len(report.violations))
    return report


def check_raw_scales(raw: Mapping) -> list[Violation]:
    """Scale violations of a raw task mapping (a scale outside SCALE_RANGE keeps it from parsing)."""
    lo, hi = SCALE_RANGE
    out = []
    for i, o in enumerate(raw.get("objects") or []):
        if not isinstance(o, Mapping) or "scale" not in o:
            continue
        name = str(o.get("name", f"objects[{i}]"))
        s = o["scale"]
        if isinstance(s, bool) or not isinstance(s, (int, float)) or not math.isfinite(s):
            out.append(Violation("scale", name, f"{name!r} has scale {s!r}; it must be a number in {lo}-{hi}"))
            continue
        if lo <= s <= hi:
            continue
        fix = (Directive.scale(name, _scale_factor(s, min(max(s, lo), hi))),) if s > 0 else ()
        out.append(Violation("scale", name, f"{name!r} has scale {s:g}, outside the allowed range {lo}-{hi}",
                             measured=float(s), limit=lo if s < lo else hi, fix=fix))
    return out


def ordered(violations: list[Violation]) -> list[Violation]:
    return sorted(violations, key=lambda v: (CHECKS.index(v.check), v.severity != "error"))
