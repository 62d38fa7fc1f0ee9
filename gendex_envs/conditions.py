"""The task language's success conditions: what each condition type takes and checks (:class:`ConditionSpec`,
:data:`CONDITION_FIELDS`), and the problems of one condition as written. :mod:`gendex_envs.success` evaluates them,
:mod:`gendex_envs.spec` holds them inside a task; ``docs/task_spec.md`` is the reference.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Literal, get_args

from gendex_envs.typed_yaml import MAX_POSITION_M, quote

ConditionType = Literal["lifted", "inside", "near", "joint_open", "rotated", "grasped", "released", "over",
                        "hand_at", "fingertips_near", "hand_open", "placed", "joint_at", "upright", "flipped",
                        "at_rest", "wiped", "hung", "poured"]
Part = Literal["handle"]
Relation = Literal["left_of", "right_of", "in_front_of", "behind", "next_to", "between", "in_region"]
Region = Literal["left", "right", "near", "far", "centre", "near_left", "near_right", "far_left", "far_right"]

CONDITION_TYPES: tuple[str, ...] = get_args(ConditionType)
RELATIONS: tuple[str, ...] = get_args(Relation)
REGIONS: tuple[str, ...] = get_args(Region)
SIDE_RELATIONS = ("left_of", "right_of", "in_front_of", "behind")
"""``placed`` relations to one target along a direction seen from the robot."""


@dataclass(frozen=True, kw_only=True)
class ConditionSpec:
    """One success condition. ``type`` says which other fields it takes (:data:`CONDITION_FIELDS`); a field that
    does not apply to the type is an error. Optional fields left out take :data:`CONDITION_DEFAULTS`."""

    type: ConditionType
    """Condition kind; one of CONDITION_TYPES."""
    object: str | None = None
    """Name of the object the condition is about (every type but ``hand_open``)."""
    target: str | None = None
    """inside: the container; near: an object or 'goal'; over: the object to be above; hung: what it hangs on; poured:
    the container the pieces go into."""
    negate: bool = False
    """True: the condition must *not* hold (e.g. ``grasped`` negated: the hand has let go)."""
    part: Part | None = None
    """grasped, released, hand_at, fingertips_near: 'handle' = the handle of an articulated object's joint instead
    of the object itself."""
    joint: str | None = None
    """joint_open, joint_at, or with ``part: handle``: the joint (default: the asset's main joint); inside: the joint
    whose link holds the object (a drawer's slide: the object lies in the drawer's bin, open or shut)."""
    min_height_m: float | None = None
    """lifted: required rise above the object's height at reset (m), > 0; hung: the least rise (default 0.05: a
    mug leant on a stand's base plate has risen 2 cm)."""
    min_fraction: float | None = None
    """joint_open: required opening as a fraction of the joint range; wiped: the share of the target's marks wiped;
    poured: the share of the object's pieces that must lie in the target; in (0, 1]."""
    max_dist_m: float | None = None
    """near: object to target; hand_at: palm to the point; fingertips_near: mean fingertip distance (m), > 0."""
    min_deg: float | None = None
    """rotated: twist about world z since reset, degrees, counter-clockwise seen from above (negative: clockwise),
    non-zero; the twist must reach it."""
    min_fingers: int | None = None
    """grasped: fingers other than the thumb that must touch (1-4; default 2)."""
    thumb: bool | None = None
    """grasped: the thumb must touch too (default true)."""
    min_force_n: float | None = None
    """grasped: a link group touches when its mean contact force exceeds this (N, > 0; default 0.3)."""
    max_palm_force_n: float | None = None
    """grasped: the palm may press with at most this mean force (N, > 0); unset: no limit."""
    max_force_n: float | None = None
    """released: no finger, thumb or palm group presses with more than this (N, > 0; default 0.3)."""
    max_xy_m: float | None = None
    """over: horizontal distance of the object from the target (m), > 0."""
    min_dz_m: float | None = None
    """over: least height of the object above the target's origin (m)."""
    max_dz_m: float | None = None
    """over: greatest height of the object above the target's origin (m), > min_dz_m."""
    ring_radius_m: float | None = None
    """hand_at: the point lies on a ring of this radius about the object's vertical axis, on the side the palm is
    (m, >= 0; default 0: on the axis)."""
    above_m: float | None = None
    """hand_at: height of the point above the object's origin (m; default 0)."""
    min_spread_m: float | None = None
    """hand_open: mean fingertip distance from the palm (m), > 0."""
    relation: Relation | None = None
    """placed: where the object lies, seen from the robot (it faces along its base's yaw; its left is the left):
    ``left_of``, ``right_of``, ``in_front_of`` (between target and the robot), ``behind`` (beyond target) and
    ``next_to`` target, ``between`` target and ``other``, or ``in_region`` of the table."""
    other: str | None = None
    """placed, relation between: the second object."""
    region: Region | None = None
    """placed, relation in_region: the part of the table (``near`` is the robot's side, ``far`` the opposite one)."""
    min_gap_m: float | None = None
    """placed: least distance of the object from target along the relation's direction (next_to: in any direction;
    between: from each of the two), centre to centre (m, >= 0; default 0.05)."""
    max_gap_m: float | None = None
    """placed: greatest distance from target along the relation's direction (next_to: in any direction), centre to
    centre (m, > min_gap_m; default 0.3)."""
    max_offset_m: float | None = None
    """placed: greatest distance across the relation's direction (between: from the line through the two) (m, > 0;
    default 0.1)."""
    fraction: float | None = None
    """joint_at: where the joint must be, as a fraction of the way from closed (0; off) to open (1; on), in [0, 1]."""
    max_error: float | None = None
    """joint_at: how far from ``fraction`` the joint may be, in the same units (in (0, 0.5]; default 0.1)."""
    max_tilt_deg: float | None = None
    """upright: how far the object's up axis (the one that pointed up at reset) may lean from world up (degrees, in
    (0, 180); default 15)."""
    min_tilt_deg: float | None = None
    """flipped: how far the object's up axis must have turned from world up (degrees, in (0, 180]; default 150: upside
    down, give or take 30)."""
    max_speed_m_s: float | None = None
    """at_rest: the fastest the object's origin may move (m/s, > 0; default 0.02)."""
    max_spin_rad_s: float | None = None
    """at_rest: the fastest the object may spin (rad/s, > 0; default 0.3)."""
    min_press_n: float | None = None
    """wiped: a mark is wiped when the object passes over it pressing on the target with at least this force (N, > 0;
    default 1.0: four times a thick sponge's weight, so one lying there, or pushed along by its side, presses too
    little)."""


CONDITION_DEFAULTS: dict[str, Any] = {"min_fingers": 2, "thumb": True, "min_force_n": 0.3, "max_force_n": 0.3,
                                      "ring_radius_m": 0.0, "above_m": 0.0, "min_gap_m": 0.05, "max_gap_m": 0.3,
                                      "max_offset_m": 0.1, "max_error": 0.1, "max_tilt_deg": 15.0,
                                      "min_tilt_deg": 150.0, "max_speed_m_s": 0.02, "max_spin_rad_s": 0.3,
                                      "min_press_n": 1.0, "min_height_m": 0.05}
"""Values of optional condition fields left out."""

CONDITION_FIELDS: dict[str, tuple[tuple[str, ...], tuple[str, ...], str]] = {
    "lifted": (("object", "min_height_m"), (), "the object has risen at least min_height_m since reset"),
    "inside": (("object", "target"), ("joint",), "the object rests inside the container target (with joint: in the "
               "space that joint's link holds, a drawer)"),
    "near": (("object", "target", "max_dist_m"), (), "the object is within max_dist_m of target (or the goal)"),
    "joint_open": (("object", "min_fraction"), ("joint",), "the joint is open at least min_fraction of its range"),
    "rotated": (("object", "min_deg"), (), "the object has turned min_deg about world z since reset"),
    "grasped": (("object",), ("part", "joint", "min_fingers", "thumb", "min_force_n", "max_palm_force_n"),
                "the thumb and at least min_fingers fingers touch the object (or its handle)"),
    "released": (("object",), ("part", "joint", "max_force_n"), "no part of the hand presses on the object"),
    "over": (("object", "target", "max_xy_m", "min_dz_m", "max_dz_m"), (),
             "the object is above target: within max_xy_m horizontally, min_dz_m..max_dz_m higher"),
    "hand_at": (("object", "max_dist_m"), ("part", "joint", "ring_radius_m", "above_m"),
                "the palm is within max_dist_m of a point by the object (its origin, a ring about it, its handle)"),
    "fingertips_near": (("object", "max_dist_m"), ("part", "joint"),
                        "the fingertips are on average within max_dist_m of the object's origin (or its handle)"),
    "hand_open": (("min_spread_m",), (), "the fingertips are on average at least min_spread_m from the palm"),
    "placed": (("object", "relation"), ("target", "other", "region", "min_gap_m", "max_gap_m", "max_offset_m"),
               "the object lies left of, right of, in front of, behind or next to target, between target and other, or "
               "in a region of the table, seen from the robot"),
    "joint_at": (("object", "fraction"), ("joint", "max_error"),
                 "the joint is within max_error of fraction of the way from closed to open"),
    "upright": (("object",), ("max_tilt_deg",), "the object stands as it stood at reset, its up axis within "
                "max_tilt_deg of world up"),
    "flipped": (("object",), ("min_tilt_deg",), "the object is turned over: its up axis at reset now points at least "
                "min_tilt_deg away from world up"),
    "at_rest": (("object",), ("max_speed_m_s", "max_spin_rad_s"), "the object is still: it moves at most "
                "max_speed_m_s and spins at most max_spin_rad_s"),
    "wiped": (("object", "target", "min_fraction"), ("min_press_n",),
              "the object has passed over at least min_fraction of target's marks (a wipe area's sites) while pressing "
              "on target with min_press_n or more; a mark once wiped stays wiped for the episode"),
    "poured": (("object", "target", "min_fraction"), (),
               "at least min_fraction of the loose pieces (objects tagged pourable: beads, marbles) that started in "
               "the vessel object lie in the container target"),
    "hung": (("object", "target"), ("min_height_m",),
             "the object hangs on target: target bears at least half its weight (the simulator's contact force "
             "between the two) and it has risen at least min_height_m since reset"),
}
"""Condition type -> (required fields, optional fields, meaning). ``type`` and ``negate`` apply to every type."""
assert set(CONDITION_FIELDS) == set(CONDITION_TYPES)


_POSITIVE = {"min_height_m", "max_dist_m", "min_force_n", "max_palm_force_n", "max_force_n", "max_xy_m",
             "min_spread_m", "max_offset_m", "max_speed_m_s", "max_spin_rad_s", "min_press_n"}


def condition_problems(c: ConditionSpec, at: str, ref) -> list[str]:
    """Problems of one condition at path ``at``; ``ref(value, path, allow_goal)`` checks an object reference."""
    required, optional, meaning = CONDITION_FIELDS[c.type]
    p: list[str] = []
    fields = required + optional
    for f in dataclasses.fields(ConditionSpec):
        if f.name in ("type", "negate") or f.name in fields or getattr(c, f.name) is None:
            continue
        p.append(f"{at}.{f.name} = {quote(getattr(c, f.name))} does not apply to type {c.type!r} ({meaning}); its "
                 f"fields: {', '.join(fields)}")
    for name in required:
        if getattr(c, name) is None:
            p.append(f"{at}.{name} is required for type {c.type!r} ({meaning})")

    def bad(name: str, allowed: str) -> None:
        p.append(f"{at}.{name} = {quote(getattr(c, name))} is not allowed; must be {allowed}")

    for name in _POSITIVE & set(fields):
        if getattr(c, name) is not None and not getattr(c, name) > 0:
            bad(name, "> 0")
    if c.min_fraction is not None and not 0 < c.min_fraction <= 1:
        bad("min_fraction", "a fraction in (0, 1]")
    if c.min_deg is not None and c.min_deg == 0:
        bad("min_deg", "non-zero (positive: counter-clockwise seen from above)")
    if c.min_fingers is not None and not 1 <= c.min_fingers <= 4:
        bad("min_fingers", "between 1 and 4 (fingers other than the thumb)")
    if c.ring_radius_m is not None and c.ring_radius_m < 0:
        bad("ring_radius_m", ">= 0")
    for f in dataclasses.fields(ConditionSpec):
        v = getattr(c, f.name)
        if f.name.endswith("_m") and v is not None and not abs(v) <= MAX_POSITION_M:
            bad(f.name, f"within +/-{MAX_POSITION_M} m (MAX_POSITION_M)")
    if c.min_dz_m is not None and c.max_dz_m is not None and not c.max_dz_m > c.min_dz_m:
        bad("max_dz_m", f"> min_dz_m ({c.min_dz_m})")
    if c.type == "placed":
        p += _placed_problems(c, at)
    if c.max_tilt_deg is not None and not 0 < c.max_tilt_deg < 180:
        bad("max_tilt_deg", "in (0, 180) degrees")
    if c.min_tilt_deg is not None and not 0 < c.min_tilt_deg <= 180:
        bad("min_tilt_deg", "in (0, 180] degrees")
    if c.fraction is not None and not 0 <= c.fraction <= 1:
        bad("fraction", "a fraction in [0, 1] (0: closed or off, 1: open or on)")
    if c.max_error is not None and not 0 < c.max_error <= 0.5:
        bad("max_error", "in (0, 0.5]")
    if c.object is not None:
        ref(c.object, f"{at}.object")
    if c.target is not None:
        if c.target == c.object:
            bad("target", "another object's name, not the condition's own object")
        else:
            ref(c.target, f"{at}.target", allow_goal=c.type == "near")
    if c.other is not None:
        if c.other in (c.object, c.target):
            bad("other", "a third object, neither the condition's object nor its target")
        else:
            ref(c.other, f"{at}.other")
    return p


def _placed_problems(c: ConditionSpec, at: str) -> list[str]:
    """What a ``placed`` condition's relation needs: a target (and for between an other), or a region alone."""
    p: list[str] = []
    r = c.relation
    wants = {"target": r != "in_region", "other": r == "between", "region": r == "in_region"}
    for name, wanted in wants.items():
        if wanted and getattr(c, name) is None:
            p.append(f"{at}.{name} is required for a placed condition with relation {r!r}")
        elif not wanted and getattr(c, name) is not None:
            p.append(f"{at}.{name} = {quote(getattr(c, name))} does not apply to relation {r!r}")
    lo = CONDITION_DEFAULTS["min_gap_m"] if c.min_gap_m is None else c.min_gap_m
    if c.min_gap_m is not None and c.min_gap_m < 0:
        p.append(f"{at}.min_gap_m = {quote(c.min_gap_m)} is not allowed; must be >= 0")
    if c.max_gap_m is not None and not c.max_gap_m > lo:
        p.append(f"{at}.max_gap_m = {quote(c.max_gap_m)} is not allowed; must be > min_gap_m ({lo})")
    if r in ("between", "in_region") and c.max_gap_m is not None:
        p.append(f"{at}.max_gap_m = {quote(c.max_gap_m)} does not apply to relation {r!r}")
    if r in ("next_to", "in_region") and c.max_offset_m is not None:
        p.append(f"{at}.max_offset_m = {quote(c.max_offset_m)} does not apply to relation {r!r}")
    if r == "in_region" and c.min_gap_m is not None:
        p.append(f"{at}.min_gap_m = {quote(c.min_gap_m)} does not apply to relation {r!r}")
    return p
