"""Where the critic's penetration fix may put an object: a free spot, and never in front of what the task works.

Two objects that overlap at reset are pulled apart by moving the smaller movable one (:mod:`generator.critic.physical`).
Pushing it along the line between the two centres is the shortest way out of the other object, but it looks at
nothing else. In a task of batch 58117 a can that stood in a pot was pushed 34 cm that way, into the space in front of
the compact microwave whose door the first stage presses shut; the pressing hand met the can, and the door stalled
at 0.25 rad on 4 of 8 dev seeds.

:func:`choose_move` therefore tries that move and then the four moves along the table's axes that clear the other
object, shortest first, and takes the first whose result a :class:`Room` admits: the object's footprint, widened by
its own randomization, stays on the table top, within the arm's reach, off every other object (widened by theirs),
and out of every *front zone*. A front zone is the strip in front (-x in the asset's frame, where doors, drawers,
handles and knobs face) of an articulated object that a stage works: as wide as the object and
:func:`front_depth` deep, the room a side door sweeps when it opens and the hand needs to press or pull it. When no
candidate fits, the line between the centres is kept, so the next critic round still sees what is wrong.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

PENETRATION_FIX_MARGIN_M = 0.01
"""Gap left between two bounding boxes moved apart by a penetration fix (m)."""
FRONT_ZONE_MIN_M = 0.15
"""Shallowest front zone (m): a knob's or a faucet's, the room the hand's palm needs in front of it."""
FRONT_ZONE_MAX_M = 0.30
"""Deepest front zone (m): the travel of the catalog's drawers; a 42 cm side door open 45 degrees reaches 0.3 m out."""


def _clearance(mover_lo, mover_hi, other_lo, other_hi, axis: int, sign: float, jitter: float) -> float:
    """How far ``mover`` must go along ``sign`` x axis ``axis`` to clear ``other`` by PENETRATION_FIX_MARGIN_M plus
    ``jitter``."""
    overlap = other_hi[axis] - mover_lo[axis] if sign > 0 else mover_hi[axis] - other_lo[axis]
    return max(float(overlap), 0.0) + PENETRATION_FIX_MARGIN_M + jitter


def separating_move(mover_lo, mover_hi, other_lo, other_hi, fallback_y: float,
                    jitter_xy: Iterable[float] = (0.0, 0.0)) -> np.ndarray:
    """xy translation of ``mover`` along the line between the box centres that separates the boxes in x or y.

    The gap left is PENETRATION_FIX_MARGIN_M plus ``jitter_xy`` (both objects' randomization half-ranges, per axis),
    so the objects stay apart at every reset.
    """
    jitter = list(jitter_xy)
    c_m, c_o = (mover_lo[:2] + mover_hi[:2]) / 2, (other_lo[:2] + other_hi[:2]) / 2
    u = c_m - c_o
    n = float(np.linalg.norm(u))
    if n < 1e-3:  # centres on one vertical line: move towards the table's centre line y = 0
        u = np.array([0.0, -1.0 if fallback_y > 0 else 1.0])
    else:
        u = u / n
    need = []
    for i in range(2):
        if abs(u[i]) < 1e-6:
            continue
        need.append(_clearance(mover_lo, mover_hi, other_lo, other_hi, i, u[i], jitter[i]) / abs(u[i]))
    t = min(need) if need else PENETRATION_FIX_MARGIN_M
    return u * t


def axis_moves(mover_lo, mover_hi, other_lo, other_hi, jitter_xy: Iterable[float]) -> list[np.ndarray]:
    """The four moves along +-x and +-y that leave the same gap as :func:`separating_move`, shortest first."""
    jitter = list(jitter_xy)
    out = []
    for i in range(2):
        for sign in (1.0, -1.0):
            d = np.zeros(2)
            d[i] = sign * _clearance(mover_lo, mover_hi, other_lo, other_hi, i, sign, jitter[i])
            out.append(d)
    return sorted(out, key=lambda d: float(np.abs(d).sum()))


def front_depth(width_y: float) -> float:
    """Depth of an articulated object's front zone: its width (a side door sweeps that far), clipped to
    [FRONT_ZONE_MIN_M, FRONT_ZONE_MAX_M]."""
    return float(min(max(width_y, FRONT_ZONE_MIN_M), FRONT_ZONE_MAX_M))


def front_zone(local_lo, local_hi, rotation: np.ndarray, origin, jitter_xy: Iterable[float],
               yaw_deg: float = 0.0) -> np.ndarray:
    """[2, 2] xy rectangle (lo, hi) in the world holding an articulated object's front zone at every reset.

    ``local_lo`` / ``local_hi``: the object's scaled bounding box in its own frame; ``rotation`` and ``origin`` place
    that frame in the world (as :func:`generator.critic.physical._place`); ``jitter_xy`` and ``yaw_deg``: its
    randomization half-ranges (the zone is swept over both).
    """
    lo, hi = np.asarray(local_lo, dtype=float), np.asarray(local_hi, dtype=float)
    depth = front_depth(hi[1] - lo[1])
    corners = np.array([[x, y, 0.0] for x in (lo[0] - depth, lo[0]) for y in (lo[1], hi[1])])
    xy = []
    for a in np.radians([-yaw_deg, 0.0, yaw_deg]):
        turn = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
        xy.append((corners @ (turn @ np.asarray(rotation)).T)[:, :2])
    world = np.concatenate(xy) + np.asarray(origin, dtype=float)[:2]
    j = np.asarray(list(jitter_xy), dtype=float)
    return np.stack([world.min(axis=0) - j, world.max(axis=0) + j])


def min_width_xy(points: np.ndarray) -> float:
    """Smallest width of the points' horizontal projection over all directions (2 degree steps)."""
    angles = np.radians(np.arange(0.0, 180.0, 2.0))
    dirs = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    proj = np.asarray(points)[:, :2] @ dirs.T
    return float((proj.max(axis=0) - proj.min(axis=0)).min())


def _apart(lo_a, hi_a, lo_b, hi_b) -> bool:
    return bool(np.any(np.asarray(hi_a) <= np.asarray(lo_b)) or np.any(np.asarray(hi_b) <= np.asarray(lo_a)))


@dataclass(frozen=True)
class Room:
    """What a moved object's box must keep to (all xy boxes as [2, 2] (lo, hi), already widened by their own
    randomization)."""

    table_half_xy: tuple[float, float]
    base_xy: tuple[float, float]
    reach_m: tuple[float, float]
    """(closest distance from the base to the footprint centre, farthest to its nearest point)."""
    obstacles: tuple[tuple[np.ndarray, np.ndarray], ...] = ()
    """Other objects' 3-D boxes (lo, hi), xy widened by their randomization."""
    zones: tuple[np.ndarray, ...] = ()
    """Front zones (:func:`front_zone`)."""

    def why_not(self, lo, hi, jitter_xy: Iterable[float]) -> str | None:
        """Why the box ``lo``..``hi`` (3-D) randomized by ``jitter_xy`` does not fit here, or None when it does."""
        j = np.asarray(list(jitter_xy), dtype=float)
        lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        flo, fhi = lo[:2] - j, hi[:2] + j
        half = np.asarray(self.table_half_xy)
        if np.any(flo < -half) or np.any(fhi > half):
            return "off the table"
        base = np.asarray(self.base_xy)
        nearest = float(np.linalg.norm(np.maximum(np.maximum(flo - base, base - fhi), 0.0)))
        centre = float(np.linalg.norm((lo[:2] + hi[:2]) / 2 - base)) - float(np.linalg.norm(j))
        if nearest > self.reach_m[1] or centre < self.reach_m[0]:
            return "out of reach"
        for olo, ohi in self.obstacles:
            if not _apart(np.r_[flo, lo[2]], np.r_[fhi, hi[2]], olo, ohi):
                return "on another object"
        for zone in self.zones:
            if not _apart(flo, fhi, zone[0], zone[1]):
                return "in front of an articulated object the task works"
        return None


def choose_move(mover_lo, mover_hi, other_lo, other_hi, room: Room, fallback_y: float,
                jitter_pair: Sequence[float], jitter_self: Sequence[float]) -> np.ndarray:
    """xy move of the mover out of the other object (module docstring): the centre-line move when the room admits
    its result, else the shortest admitted axis move, else the centre-line move."""
    lo, hi = np.asarray(mover_lo, dtype=float), np.asarray(mover_hi, dtype=float)
    line = separating_move(lo, hi, other_lo, other_hi, fallback_y, jitter_pair)
    for d in [line, *axis_moves(lo, hi, other_lo, other_hi, jitter_pair)]:
        shift = np.r_[d, 0.0]
        if room.why_not(lo + shift, hi + shift, jitter_self) is None:
            return d
    return line
