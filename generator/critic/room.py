"""The critic's ``structure_room`` check: a scene's fixed structures must leave the arm room to work.

A task's ``scene`` (:mod:`gendex_envs.scene_spec`, its style's structures when it names none) may stand shelves,
counters or a fume hood anywhere. The motion planner sees them (:func:`gendex.solve.collision.structure_obstacles`)
and goes round them or refuses, but a structure in the wrong place leaves it nothing to go round to. Each colliding
box of each structure (:func:`gendex_envs.scene_geometry.structure_boxes`, its world axis-aligned box) is an error
when it

* stands within :data:`BASE_CLEAR_M` (horizontally) of the robot base's axis, at any height: the shoulder and the
  elbow turn there;
* reaches into the **arm's room over the table**: the table top's footprint, from the table top up to
  :data:`ARM_ROOM_HEIGHT_M`, within :data:`~generator.critic.physical.REACH_MAX_M` of the base (horizontally): where
  the hand works and the arm's links pass above it. Beyond the reach (the far end of the table) a structure may
  stand on the table;
* (the whole structure, every part) overlaps an object's start region above the table top: its footprint widened
  by its randomization (turned any way when its yaw is randomized) and
  :data:`~gendex_envs.scene_geometry.STRUCTURE_GAP_M`. The env refuses such a scene when it builds
  (:meth:`gendex_envs.scene.Scenery.build`); this check is a little more cautious (world bounding boxes).

No directive moves a structure: the message names the structure, where it is and what it blocks; the fix is another
place (``pos_m``, ``anchor``), another style or ``structures: []``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from gendex_envs.scene_geometry import STRUCTURE_GAP_M, scene_structure_boxes, structure_boxes
from gendex_envs.scene_spec import resolve_scene

if TYPE_CHECKING:  # pragma: no cover
    from gendex_envs.spec import TaskSpec
    from generator.critic.physical import Placed, Violation

BASE_CLEAR_M = 0.35
"""No structure within this horizontal distance of the robot base's axis (m): the shoulder (a 0.08 m housing) turns
there and the upper arm rises from it; the same distance as the closest object the hand folds back to
(:data:`~generator.critic.physical.REACH_MIN_M`)."""
ARM_ROOM_HEIGHT_M = 0.9
"""Height above the table top the arm's room over the table reaches (m). Measured: with the palm turned down at 252
collision-free poses over the table (x -0.4..0.6, y -0.55..0.55, 5-35 cm up), the arm's highest link sphere (the
elbow) tops out 0.50-0.86 m above the table top (median 0.82; 0.86 at the rest pose)."""
WHY = ("move it beside the table (anchor left_edge or right_edge, out past the edge), beyond the arm's reach, or "
       "choose another style or structures: []")


def structure_room(spec: TaskSpec, placed: dict[str, Placed], meas: dict, violations: list[Violation]) -> None:
    """Append a ``structure_room`` violation per structure that leaves the arm or an object no room (module
    docstring); ``meas``: structure name -> its kind, its nearest distance to the base's axis and how far it
    reaches into the arm's room (m), and the objects' start regions it overlaps."""
    from generator.critic.physical import REACH_MAX_M, Violation, rounded

    if spec.scene is None:
        return
    scene = resolve_scene(spec.scene)
    base = np.asarray(spec.robot.base_pos_m[:2], dtype=float)
    sx, sy = spec.table.size_m
    room_lo, room_hi = np.array([-sx / 2, -sy / 2, 0.0]), np.array([sx / 2, sy / 2, ARM_ROOM_HEIGHT_M])
    by_structure: dict[str, list] = {}
    for box in scene_structure_boxes(scene, spec.table):
        by_structure.setdefault(box.structure, []).append(box)
    for s in scene.structures:
        boxes = by_structure.get(s.name, [])
        if not boxes:
            continue
        lo, hi = np.min([b.lo for b in boxes], axis=0), np.max([b.hi for b in boxes], axis=0)
        near_base = min(_xy_distance(base, b.lo, b.hi) for b in boxes)
        inside = []  # the parts of its boxes in the arm's room
        for b in boxes:
            clip_lo, clip_hi = np.maximum(b.lo, room_lo), np.minimum(b.hi, room_hi)
            if np.all(clip_hi > clip_lo) and _xy_distance(base, clip_lo, clip_hi) <= REACH_MAX_M:
                inside.append((clip_lo, clip_hi))
        # how far into the room it reaches: the shortest extent of what is inside (the shortest way out)
        depth = float(np.min(np.max([h for _, h in inside], axis=0) - np.min([q for q, _ in inside], axis=0))
                      ) if inside else 0.0
        meas[s.name] = {"kind": s.kind, "nearest_base_m": rounded(near_base), "in_arm_room_m": rounded(depth)}
        where = (f"scene structure {s.name!r} ({s.kind}) covers x {lo[0]:.2f}..{hi[0]:.2f}, "
                 f"y {lo[1]:.2f}..{hi[1]:.2f}, z {lo[2]:.2f}..{hi[2]:.2f} m")
        if near_base < BASE_CLEAR_M:
            violations.append(Violation(
                "structure_room", None, f"{where} and stands {near_base:.2f} m from the robot base's axis (at least "
                f"{BASE_CLEAR_M} m: the shoulder and elbow turn there); {WHY}", measured=near_base,
                limit=BASE_CLEAR_M, other=f"structure:{s.name}"))
        elif depth > 0.0:
            violations.append(Violation(
                "structure_room", None, f"{where} and reaches {depth:.2f} m into the arm's room over the table (the "
                f"table top within {REACH_MAX_M} m of the base, up to {ARM_ROOM_HEIGHT_M} m above it), where the hand "
                f"works and the arm passes; {WHY}", measured=depth, limit=0.0, other=f"structure:{s.name}"))
    _objects(scene.structures, spec, placed, meas, violations)


def _objects(structures, spec: TaskSpec, placed: dict[str, Placed], meas: dict, violations: list[Violation]) -> None:
    """The env's own refusal (:meth:`gendex_envs.scene.Scenery._check_room`), as a violation: a structure's whole
    box over the table top overlapping an object's start region."""
    from generator.critic.physical import Violation, rounded

    boxes: dict[str, list] = {}
    for b in structure_boxes(structures, spec.table, collision_only=False):
        boxes.setdefault(b.structure, []).append(b)
    for s in structures:
        parts = boxes.get(s.name, [])
        if not parts:
            continue
        lo = np.min([b.lo for b in parts], axis=0)
        hi = np.max([b.hi for b in parts], axis=0)
        if hi[2] <= 0.0 and s.on_floor:
            continue  # wholly below the table top
        for name, p in placed.items():
            half = (p.hi[:2] - p.lo[:2]) / 2
            if p.spec.randomize.yaw_deg > 0:
                half = np.full(2, float(np.linalg.norm(half)))
            centre = p.centre_xy
            reach = half + np.asarray(p.spec.randomize.xy_m, dtype=float) + STRUCTURE_GAP_M
            depth = float(np.min(np.minimum(hi[:2], centre + reach) - np.maximum(lo[:2], centre - reach)))
            if depth <= 0.0:
                continue
            meas.setdefault(s.name, {"kind": s.kind}).setdefault("overlaps", {})[name] = rounded(depth)
            violations.append(Violation(
                "structure_room", None, f"scene structure {s.name!r} ({s.kind}) covers x {lo[0]:.2f}..{hi[0]:.2f}, y "
                f"{lo[1]:.2f}..{hi[1]:.2f} m and overlaps the start region of {name!r} (its footprint, randomization "
                f"and {STRUCTURE_GAP_M} m) by {depth:.3f} m: the env refuses to build that; {WHY}", measured=depth,
                limit=0.0, other=name))


def _xy_distance(point: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> float:
    """Horizontal distance from ``point`` [2] to the rectangle ``lo[:2]``..``hi[:2]`` (0 inside)."""
    gap = np.maximum(np.maximum(lo[:2] - point, point - hi[:2]), 0.0)
    return float(math.hypot(*gap))


__all__ = ["ARM_ROOM_HEIGHT_M", "BASE_CLEAR_M", "structure_room"]
