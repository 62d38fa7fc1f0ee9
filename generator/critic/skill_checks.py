"""The critic's checks of what a skill needs of a scene, beyond the physical ones (:mod:`generator.critic.physical`
calls them among its static checks, with the same :class:`~generator.critic.physical.Violation` records and fixes).

``handover``
    An object the success leaves on a hand-over zone (an asset tagged ``handover``) must start clear of it: the
    object's footprint and the zone's, each widened by its randomization, at least :data:`HANDOVER_APART_M` apart.
    Nearer, a task is half done at reset (a nudge finishes it), and a start on the mat is done by holding still.
    Fix: the object moves away from the zone along the axis it is already most apart on (towards the robot when it
    starts on the zone's middle) until that axis alone leaves the gap.
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


def handover_checks(spec: TaskSpec, placed: dict[str, Placed], meas: dict, violations: list[Violation]) -> None:
    """The ``handover`` check (module docstring): one violation per object that starts too near its zone."""
    from generator.critic.physical import Violation, moves, rounded

    for c in spec.success.conditions:
        if (c.negate or c.type not in (*SET_DOWN_CONDITIONS, "placed") or c.target not in placed
                or c.object not in placed or "handover" not in placed[c.target].record.tags):
            continue
        obj, zone = placed[c.object], placed[c.target]
        wo, wz = np.asarray(obj.spec.randomize.xy_m), np.asarray(zone.spec.randomize.xy_m)
        o_lo, o_hi = obj.lo[:2] - wo, obj.hi[:2] + wo
        z_lo, z_hi = zone.lo[:2] - wz, zone.hi[:2] + wz
        gaps = _gaps(o_lo, o_hi, z_lo, z_hi)
        gap = float(np.linalg.norm(gaps))
        meas[c.object] = {"zone": c.target, "gap_m": rounded(gap), "limit_m": HANDOVER_APART_M}
        if gap >= HANDOVER_APART_M:
            continue
        d = obj.centre_xy - zone.centre_xy
        axis = int(np.argmax(np.abs(d))) if np.abs(d).max() > 0.01 else 0
        sign = 1.0 if d[axis] > 0.01 else -1.0  # on the mat: towards the robot
        step = np.zeros(2)
        step[axis] = (z_hi[axis] + HANDOVER_APART_M - o_lo[axis] if sign > 0
                      else z_lo[axis] - HANDOVER_APART_M - o_hi[axis]) + sign * 1e-3
        violations.append(Violation(
            "handover", c.object, f"{c.object!r} starts {gap:.3f} m from the hand-over zone {c.target!r} (footprints "
            f"widened by their randomization); a hand-over carries it at least {HANDOVER_APART_M} m",
            measured=gap, limit=HANDOVER_APART_M, fix=moves(c.object, step), other=c.target))


__all__ = ["HANDOVER_APART_M", "handover_checks"]
