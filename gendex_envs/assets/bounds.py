"""World-space bounds of built entities, from their PhysX collision shapes (CPU scenes; for checks, not per step)."""

from __future__ import annotations

import numpy as np
import sapien
from mani_skill.utils.structs import Articulation
from sapien import physx

from gendex_envs.physx import px_bodies, px_objects

_RING = np.stack([np.cos(np.linspace(0, 2 * np.pi, 16, endpoint=False)),
                  np.sin(np.linspace(0, 2 * np.pi, 16, endpoint=False))], axis=1)  # [16, 2]


def shape_points(shape) -> np.ndarray:
    """[K, 3] points whose convex hull encloses (or, for round shapes, closely approximates) ``shape``, local frame."""
    if isinstance(shape, physx.PhysxCollisionShapeConvexMesh):
        return np.asarray(shape.vertices) * np.asarray(shape.scale)
    if isinstance(shape, physx.PhysxCollisionShapeBox):
        h = np.asarray(shape.half_size)
        return np.array([[x, y, z] for x in (-h[0], h[0]) for y in (-h[1], h[1]) for z in (-h[2], h[2])])
    if isinstance(shape, physx.PhysxCollisionShapeSphere):
        r = shape.radius
        return np.array([[sx * r, 0, 0] for sx in (-1, 1)] + [[0, sy * r, 0] for sy in (-1, 1)]
                        + [[0, 0, sz * r] for sz in (-1, 1)])
    if isinstance(shape, physx.PhysxCollisionShapeCylinder | physx.PhysxCollisionShapeCapsule):
        r, h = shape.radius, shape.half_length  # SAPIEN cylinders and capsules run along local x
        ends = (-h - r, h + r) if isinstance(shape, physx.PhysxCollisionShapeCapsule) else (-h, h)
        ring = np.concatenate([np.zeros((16, 1)), r * _RING], axis=1)
        return np.concatenate([ring + [x, 0, 0] for x in ends])
    if isinstance(shape, physx.PhysxCollisionShapeTriangleMesh):
        return np.asarray(shape.vertices) * np.asarray(shape.scale)
    raise TypeError(f"no bounds for collision shape {type(shape).__name__}")


def body_points(body_pose: sapien.Pose, shapes) -> np.ndarray:
    """[K, 3] world points of a rigid body's collision shapes."""
    out = []
    for shape in shapes:
        m = (body_pose * shape.local_pose).to_transformation_matrix()
        pts = shape_points(shape)
        out.append(pts @ m[:3, :3].T + m[:3, 3])
    return np.concatenate(out) if out else np.zeros((0, 3))


def entity_aabb(entity) -> tuple[np.ndarray, np.ndarray]:
    """World AABB (min [3], max [3]) of a ManiSkill Actor or Articulation (first sub-scene)."""
    if isinstance(entity, Articulation):
        bodies = [px_objects(link)[0] for link in entity.get_links()]
        pts = np.concatenate([body_points(b.entity_pose, b.collision_shapes) for b in bodies])
    else:
        body = px_bodies(entity)[0]
        pts = body_points(body.entity.pose, body.collision_shapes)
    return pts.min(axis=0), pts.max(axis=0)
