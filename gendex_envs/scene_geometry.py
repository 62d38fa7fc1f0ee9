"""Where a scene's fixed structures stand, as boxes in the world: what the env builds, what the arm's motion planner
avoids (:mod:`gendex.solve.collision`) and what the critic checks leave the arm room (:mod:`generator.critic.room`).

Numpy only (no simulator): a structure of the spec (:class:`~gendex_envs.scene_spec.StructureSpec`) is placed by its
anchor on the table, its offset and its yaw, its base on the table top (z = 0) or on the floor (z = -table height);
each of its parts (:data:`gendex_envs.assets.structures.STRUCTURES`) is a box at a pose in the world.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from gendex_envs.assets.structures import STRUCTURES
from gendex_envs.scene_spec import ResolvedScene, SceneSpec, StructureSpec, resolve_scene

STRUCTURE_GAP_M = 0.02
"""Least gap between a structure and an object's start region or the robot's base (the env refuses less)."""
ROBOT_BASE_HALF_M = 0.15
"""Half side of the square around the arm's base no structure may enter (the env refuses it)."""


def structure_pose(spec: StructureSpec, table) -> np.ndarray:
    """[4, 4] world pose of a structure's frame (its footprint's centre on what it stands on, turned by its yaw)."""
    sx, sy = table.size_m
    anchors = {"table": (0.0, 0.0), "far_edge": (sx / 2, 0.0), "left_edge": (0.0, sy / 2), "right_edge": (0.0, -sy / 2)}
    ax, ay = anchors[spec.anchor]
    a = math.radians(spec.yaw_deg)
    pose = np.eye(4)
    pose[:3, :3] = [[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]]
    pose[:3, 3] = [ax + spec.pos_m[0], ay + spec.pos_m[1], spec.pos_m[2] - (table.height_m if spec.on_floor else 0.0)]
    return pose


@dataclass(frozen=True)
class StructureBox:
    """One box of a placed structure: its full size and the world pose of its centre."""

    structure: str
    """The structure's name in the spec."""
    kind: str
    """Its catalog kind (``shelf``, ``sink``...)."""
    index: int
    """Its position in the scene's ``structures``."""
    size_m: tuple[float, float, float]
    pose: np.ndarray
    """[4, 4] world pose of the box's centre."""
    collision: bool = True

    @property
    def corners(self) -> np.ndarray:
        """[8, 3] world corners."""
        h = np.asarray(self.size_m, dtype=float) / 2
        local = np.array([[x, y, z] for x in (-h[0], h[0]) for y in (-h[1], h[1]) for z in (-h[2], h[2])])
        return local @ self.pose[:3, :3].T + self.pose[:3, 3]

    @property
    def lo(self) -> np.ndarray:
        """Min corner of its world axis-aligned box."""
        return self.corners.min(axis=0)

    @property
    def hi(self) -> np.ndarray:
        return self.corners.max(axis=0)


def structure_boxes(structures: Iterable[StructureSpec], table, collision_only: bool = True) -> list[StructureBox]:
    """Every part of every structure as a world box (only the colliding ones with ``collision_only``)."""
    out = []
    for i, s in enumerate(structures):
        pose = structure_pose(s, table)
        for part in STRUCTURES[s.kind].parts:
            if collision_only and not part.collision:
                continue
            at = pose.copy()
            at[:3, 3] = pose[:3, :3] @ np.asarray(part.center_m, dtype=float) + pose[:3, 3]
            out.append(StructureBox(s.name, s.kind, i, tuple(part.size_m), at, part.collision))
    return out


def scene_structure_boxes(scene: SceneSpec | ResolvedScene | None, table) -> list[StructureBox]:
    """The colliding boxes of a scene's structures (its style's when it leaves them out); none without a scene."""
    if scene is None:
        return []
    resolved = scene if isinstance(scene, ResolvedScene) else resolve_scene(scene)
    return structure_boxes(resolved.structures, table)
