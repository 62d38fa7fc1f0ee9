"""The critic's checks of what a skill needs of a scene, beyond the physical ones (:mod:`generator.critic.physical`
calls them among its static checks, with the same :class:`~generator.critic.physical.Violation` records and fixes).

``handover``
    An object the success leaves on a hand-over zone (an asset tagged ``handover``) must start clear of it: the
    object's footprint and the zone's, each widened by its randomization, at least :data:`HANDOVER_APART_M` apart.
    Nearer, a task is half done at reset (a nudge finishes it), and a start on the mat is done by holding still.
    Fix: the object moves away from the zone along the axis it is already most apart on (towards the robot when it
    starts on the zone's middle) until that axis alone leaves the gap.
``insert``
    The same for a peg and the holder it goes into (an asset tagged ``insert``): a peg that starts next to its hole
    is half inserted by a nudge. Gap :data:`INSERT_APART_M`, the same fix.
``wipe``
    The same for a sponge and the spill it wipes (an asset tagged ``wipe_area``): a sponge that starts on the spill
    is half way there. Gap :data:`WIPE_APART_M`, the same fix.
``hang``
    The same for a mug and the stand it hangs on (an asset tagged ``hang_on``): a mug that starts against the stand's
    base leaves no room to grasp it clear of the pegs. Gap :data:`HANG_APART_M`, the same fix.
``pour``
    The same for a vessel and the container it pours into (a ``poured`` condition): a vessel that starts against the
    bowl leaves the hand no room to grasp it, and tipped where it stands it pours half its pieces in. Gap
    :data:`POUR_APART_M`, the same fix.
``flip``
    Every other object must start at least :data:`FLIP_ROOM_M` from an object the success turns over (``flipped``),
    footprints widened by their randomization: the glass is raised, turned about the hand and let go onto its rim
    where it stood, and the hand sweeps round it. Fix: the other object moves away along the axis it is already most
    apart on.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from gendex_envs.success import SET_DOWN_CONDITIONS

if TYPE_CHECKING:  # pragma: no cover
    from gendex_envs.spec import TaskSpec
    from generator.critic.physical import Placed, Violation

HANDOVER_APART_M = 0.1
"""Least gap (m) between an object's footprint and the hand-over zone's it is to be left on, both widened by their
randomization: the carry is then at least this long."""


def _gaps(a_lo, a_hi, b_lo, b_hi) -> np.ndarray:
    """Per-axis (x, y) gap between two rectangles (0 where they overlap along that axis)."""
    return np.maximum(0.0, np.maximum(b_lo - a_hi, a_lo - b_hi))


def _clear_step(m_lo, m_hi, f_lo, f_hi, d: np.ndarray, gap_m: float) -> np.ndarray:
    """The xy move that takes the rectangle ``m_lo..m_hi`` ``gap_m`` clear of ``f_lo..f_hi`` along the axis its centre
    is already most apart on (``d``: its centre minus the other's; where they share a centre, towards the robot)."""
    axis = int(np.argmax(np.abs(d))) if np.abs(d).max() > 0.01 else 0
    sign = 1.0 if d[axis] > 0.01 else -1.0
    step = np.zeros(2)
    step[axis] = (f_hi[axis] + gap_m - m_lo[axis] if sign > 0 else f_lo[axis] - gap_m - m_hi[axis]) + sign * 1e-3
    return step


INSERT_APART_M = 0.05
"""Least gap (m) between a peg's footprint and its holder's, both widened by their randomization (a peg must be
lifted over the holder's 5 cm wall: a nudge inserts nothing)."""
WIPE_APART_M = 0.03
"""Least gap (m) between a sponge's footprint and its spill's, both widened by their randomization."""
HANG_APART_M = 0.05
"""Least gap (m) between a mug's footprint and its stand's, both widened by their randomization."""
POUR_APART_M = 0.05
"""Least gap (m) between a vessel's footprint and the container it pours into, both widened by their
randomization."""
FLIP_ROOM_M = 0.1
"""Least gap (m) between an object to turn over and any other object, both footprints widened by their
randomization."""
_CARRIED = (*SET_DOWN_CONDITIONS, "placed", "wiped", "hung")
APART: dict[str, tuple[str, float, str, tuple[str, ...]]] = {
    "handover": ("handover", HANDOVER_APART_M, "hand-over zone", _CARRIED),
    "insert": ("insert", INSERT_APART_M, "holder", _CARRIED),
    "wipe": ("wipe_area", WIPE_APART_M, "spill", _CARRIED),
    "hang": ("hang_on", HANG_APART_M, "stand", _CARRIED),
    "pour": ("container", POUR_APART_M, "container", ("poured",))}
"""Check -> (the target's catalog tag, least gap, what the target is called, the success conditions it checks)."""


def skill_checks(spec: TaskSpec, placed: dict[str, Placed], meas: dict[str, dict],
                 violations: list[Violation]) -> None:
    """Every check of :data:`APART` (module docstring), each measured into ``meas[check]``: one violation per object
    that starts too near the target its success takes it to."""
    for check in APART:
        _apart_checks(check, spec, placed, meas[check], violations)
    _room_checks(spec, placed, meas["flip"], violations)


def _room_checks(spec: TaskSpec, placed: dict[str, Placed], meas: dict, violations: list[Violation]) -> None:
    """The ``flip`` check (module docstring)."""
    from generator.critic.physical import Violation, moves, rounded

    for c in spec.success.conditions:
        if c.negate or c.type != "flipped" or c.object not in placed:
            continue
        obj = placed[c.object]
        wo = np.asarray(obj.spec.randomize.xy_m)
        o_lo, o_hi = obj.lo[:2] - wo, obj.hi[:2] + wo
        for name, other in placed.items():
            if name == c.object:
                continue
            w = np.asarray(other.spec.randomize.xy_m)
            n_lo, n_hi = other.lo[:2] - w, other.hi[:2] + w
            gap = float(np.linalg.norm(_gaps(o_lo, o_hi, n_lo, n_hi)))
            meas[f"{c.object}/{name}"] = {"gap_m": rounded(gap), "limit_m": FLIP_ROOM_M}
            if gap >= FLIP_ROOM_M:
                continue
            step = _clear_step(n_lo, n_hi, o_lo, o_hi, other.centre_xy - obj.centre_xy, FLIP_ROOM_M)
            violations.append(Violation(
                "flip", name, f"{name!r} starts {gap:.3f} m from {c.object!r}, which is turned over where it stands "
                f"(footprints widened by their randomization); it must be at least {FLIP_ROOM_M} m away",
                measured=gap, limit=FLIP_ROOM_M, fix=moves(name, step), other=c.object))


def _apart_checks(check: str, spec: TaskSpec, placed: dict[str, Placed], meas: dict,
                  violations: list[Violation]) -> None:
    from generator.critic.physical import Violation, moves, rounded

    tag, apart, called, kinds = APART[check]
    for c in spec.success.conditions:
        if (c.negate or c.type not in kinds or c.target not in placed
                or c.object not in placed or tag not in placed[c.target].record.tags):
            continue
        obj, zone = placed[c.object], placed[c.target]
        wo, wz = np.asarray(obj.spec.randomize.xy_m), np.asarray(zone.spec.randomize.xy_m)
        o_lo, o_hi = obj.lo[:2] - wo, obj.hi[:2] + wo
        z_lo, z_hi = zone.lo[:2] - wz, zone.hi[:2] + wz
        gaps = _gaps(o_lo, o_hi, z_lo, z_hi)
        gap = float(np.linalg.norm(gaps))
        meas[c.object] = {"zone": c.target, "gap_m": rounded(gap), "limit_m": apart}
        if gap >= apart:
            continue
        step = _clear_step(o_lo, o_hi, z_lo, z_hi, obj.centre_xy - zone.centre_xy, apart)
        violations.append(Violation(
            check, c.object, f"{c.object!r} starts {gap:.3f} m from the {called} {c.target!r} (footprints widened by "
            f"their randomization); it must be carried at least {apart} m",
            measured=gap, limit=apart, fix=moves(c.object, step), other=c.target))


__all__ = ["APART", "FLIP_ROOM_M", "HANDOVER_APART_M", "HANG_APART_M", "INSERT_APART_M", "POUR_APART_M", "WIPE_APART_M",
           "skill_checks"]
