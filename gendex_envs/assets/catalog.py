"""The asset catalog: one typed :class:`AssetRecord` per object the task YAML may reference.

This first catalog holds procedural, primitive-geometry objects at real-world metric size, built directly with
SAPIEN shapes (so every collision shape is convex and exact, nothing is downloaded or decomposed at run time).
Each record knows how to build itself into a ManiSkill scene at a given uniform scale.

Frame convention of every asset: origin on the axis of symmetry at the object's lowest point (the table contact
point in its rest pose), z up. ``bbox_min_m``/``bbox_max_m`` are the axis-aligned bounds in that frame at scale 1.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import sapien

from gendex_envs.errors import AssetNotFoundError, suggest

log = logging.getLogger(__name__)

PROCEDURAL_SOURCE = "gendex procedural (primitives)"
PROCEDURAL_LICENCE = "Apache-2.0 (GenDex)"

# cylinders and capsules in SAPIEN run along x; this turns them upright (x -> z)
UPRIGHT = sapien.Pose(q=[0.7071068, 0.0, -0.7071068, 0.0])


@dataclass(frozen=True)
class JointRecord:
    """One movable joint of an articulated asset."""

    name: str
    type: str
    """"revolute" or "prismatic"."""
    limits: tuple[float, float]
    """Lower and upper limit (rad or m)."""
    closed_qpos: float
    open_qpos: float
    """Semantic targets: the joint value meaning "closed" and "open"."""
    handle_link: str
    """Link carrying the handle that opens this joint."""
    handle_point_m: tuple[float, float, float]
    """Centre of the handle's grip in the handle link's frame at scale 1 (m)."""


@dataclass(frozen=True)
class AssetRecord:
    """What GenDex knows about one asset."""

    id: str
    category: str
    source: str
    licence: str
    tags: tuple[str, ...]
    bbox_min_m: tuple[float, float, float]
    bbox_max_m: tuple[float, float, float]
    mass_kg: float
    friction: float
    build: Callable[..., object] = field(repr=False, compare=False)
    """``build(scene, name, scale, rgba, fixed, pose, record) -> Actor | Articulation`` (fixed: kinematic actor or
    fixed-root articulation; ``pose`` is the initial world pose of the asset frame)."""
    joints: tuple[JointRecord, ...] = ()

    @property
    def articulated(self) -> bool:
        return bool(self.joints)

    @property
    def size_m(self) -> tuple[float, float, float]:
        """Bounding-box size (x, y, z) at scale 1, metres."""
        return tuple(float(b - a) for a, b in zip(self.bbox_min_m, self.bbox_max_m))

    def joint(self, name: str) -> JointRecord:
        for j in self.joints:
            if j.name == name:
                return j
        raise AssetNotFoundError(
            f"asset {self.id!r} has no joint {name!r}; joints: {[j.name for j in self.joints]}."
            f"{suggest(name, [j.name for j in self.joints])}"
        )


def _material(rgba) -> sapien.render.RenderMaterial:
    return sapien.render.RenderMaterial(base_color=list(rgba), roughness=0.6)


def _physx_material(scene, friction: float):
    return sapien.physx.PhysxMaterial(static_friction=friction, dynamic_friction=0.8 * friction, restitution=0.0)


def _finish(builder, name: str, fixed: bool, pose: sapien.Pose):
    """Fixed objects are kinematic, so that resets can still place them."""
    builder.initial_pose = pose
    return builder.build_kinematic(name) if fixed else builder.build(name)


def _density(mass_kg: float, volume_m3: float) -> float:
    return mass_kg / volume_m3


def build_apple(scene, name: str, scale: float, rgba, fixed: bool, pose: sapien.Pose, record: AssetRecord):
    r = 0.04 * scale
    b = scene.create_actor_builder()
    mat = _physx_material(scene, record.friction)
    dens = _density(record.mass_kg * scale**3, 4 / 3 * np.pi * 0.04**3 * scale**3)
    b.add_sphere_collision(sapien.Pose(p=[0, 0, r]), r, material=mat, density=dens)
    b.add_sphere_visual(sapien.Pose(p=[0, 0, r]), r, material=_material(rgba or (0.78, 0.08, 0.06, 1)))
    b.add_capsule_visual(sapien.Pose(p=[0, 0, 2 * r + 0.006 * scale]) * UPRIGHT, 0.003 * scale, 0.006 * scale,
                         material=_material((0.35, 0.22, 0.1, 1)))
    return _finish(b, name, fixed, pose)


BOWL_SEGMENTS = 16


def build_bowl(scene, name: str, scale: float, rgba, fixed: bool, pose: sapien.Pose, record: AssetRecord):
    """A bowl from a flat base disc and a ring of tilted wall plates (each plate a convex box)."""
    base_r, top_r, height, wall = 0.05 * scale, 0.085 * scale, 0.06 * scale, 0.006 * scale
    b = scene.create_actor_builder()
    mat = _physx_material(scene, record.friction)
    look = _material(rgba or (0.85, 0.85, 0.8, 1))
    vol_base = np.pi * base_r**2 * wall
    slant = float(np.hypot(top_r - base_r, height))
    seg_w = 2 * np.pi * (base_r + top_r) / 2 / BOWL_SEGMENTS * 1.08
    vol_walls = BOWL_SEGMENTS * seg_w * slant * wall
    dens = _density(record.mass_kg * scale**3, vol_base + vol_walls)
    b.add_cylinder_collision(sapien.Pose(p=[0, 0, wall / 2]) * UPRIGHT, base_r, wall / 2, material=mat, density=dens)
    b.add_cylinder_visual(sapien.Pose(p=[0, 0, wall / 2]) * UPRIGHT, base_r, wall / 2, material=look)
    tilt = float(np.arctan2(top_r - base_r, height))  # from vertical, outwards
    mid_r = (base_r + top_r) / 2
    for k in range(BOWL_SEGMENTS):
        yaw = 2 * np.pi * k / BOWL_SEGMENTS
        q_yaw = sapien.Pose(q=[np.cos(yaw / 2), 0, 0, np.sin(yaw / 2)])
        q_tilt = sapien.Pose(q=[np.cos(tilt / 2), 0, np.sin(tilt / 2), 0])
        pose = sapien.Pose(p=[mid_r * np.cos(yaw), mid_r * np.sin(yaw), height / 2]) * q_yaw * q_tilt
        half = [wall / 2, seg_w / 2, slant / 2]
        b.add_box_collision(pose, half, material=mat, density=dens)
        b.add_box_visual(pose, half, material=look)
    return _finish(b, name, fixed, pose)


def build_bottle(scene, name: str, scale: float, rgba, fixed: bool, pose: sapien.Pose, record: AssetRecord):
    body_r, body_h = 0.033 * scale, 0.15 * scale
    neck_r, neck_h = 0.014 * scale, 0.05 * scale
    b = scene.create_actor_builder()
    mat = _physx_material(scene, record.friction)
    dens = _density(record.mass_kg * scale**3, np.pi * (body_r**2 * body_h + neck_r**2 * neck_h))
    look = _material(rgba or (0.1, 0.45, 0.75, 1))
    b.add_cylinder_collision(sapien.Pose(p=[0, 0, body_h / 2]) * UPRIGHT, body_r, body_h / 2, material=mat,
                             density=dens)
    b.add_cylinder_visual(sapien.Pose(p=[0, 0, body_h / 2]) * UPRIGHT, body_r, body_h / 2, material=look)
    b.add_cylinder_collision(sapien.Pose(p=[0, 0, body_h + neck_h / 2]) * UPRIGHT, neck_r, neck_h / 2, material=mat,
                             density=dens)
    b.add_cylinder_visual(sapien.Pose(p=[0, 0, body_h + neck_h / 2]) * UPRIGHT, neck_r, neck_h / 2,
                          material=_material((0.9, 0.9, 0.9, 1)))
    return _finish(b, name, fixed, pose)


CABINET_SIZE_M = (0.36, 0.50, 0.55)
"""Outer depth (x), width (y), height (z) of the hinged-door cabinet at scale 1."""


def build_cabinet(scene, name: str, scale: float, rgba, fixed: bool, pose: sapien.Pose, record: AssetRecord):
    """A box cabinet whose door faces -x (towards the robot), hinged on its +y edge, with a vertical bar handle."""
    dx, dy, dz = (s * scale for s in CABINET_SIZE_M)
    t = 0.015 * scale
    look = _material(rgba or (0.62, 0.45, 0.3, 1))
    metal = _material((0.75, 0.75, 0.78, 1))
    mat = _physx_material(scene, record.friction)
    ab = scene.create_articulation_builder()
    body = ab.create_link_builder()
    body.set_name("body")
    walls = [  # (centre, half size) of back, left, right, bottom, top panels
        ((dx / 2 - t / 2, 0, dz / 2), (t / 2, dy / 2, dz / 2)),
        ((0, -dy / 2 + t / 2, dz / 2), (dx / 2, t / 2, dz / 2)),
        ((0, dy / 2 - t / 2, dz / 2), (dx / 2, t / 2, dz / 2)),
        ((0, 0, t / 2), (dx / 2, dy / 2, t / 2)),
        ((0, 0, dz - t / 2), (dx / 2, dy / 2, t / 2)),
    ]
    for c, h in walls:
        body.add_box_collision(sapien.Pose(p=c), h, material=mat)
        body.add_box_visual(sapien.Pose(p=c), h, material=look)
    door = ab.create_link_builder(body)
    door.set_name("door")
    door.set_joint_name("door_hinge")
    hinge = sapien.Pose(p=[-dx / 2 - t / 2, dy / 2, 0], q=[0.7071068, 0, -0.7071068, 0])  # joint x-axis -> world z
    lo, hi = record.joints[0].limits
    door.set_joint_properties("revolute", limits=[[lo, hi]], pose_in_parent=hinge, pose_in_child=hinge,
                              friction=0.05, damping=0.5)
    door_c = sapien.Pose(p=[-dx / 2 - t / 2, 0, dz / 2])
    door.add_box_collision(door_c, (t / 2, dy / 2, dz / 2), material=mat, density=300)
    door.add_box_visual(door_c, (t / 2, dy / 2, dz / 2), material=look)
    # handle: vertical bar 4 cm in front of the door near its free (-y) edge, on two standoffs
    hx, hy, hz = -dx / 2 - t - 0.035 * scale, -dy / 2 + 0.06 * scale, dz / 2
    bar = sapien.Pose(p=[hx, hy, hz]) * UPRIGHT
    door.add_cylinder_collision(bar, 0.011 * scale, 0.07 * scale, material=mat, density=300)
    door.add_cylinder_visual(bar, 0.011 * scale, 0.07 * scale, material=metal)
    front_x = -dx / 2 - t
    standoff_half = ((front_x - hx) / 2, 0.006 * scale, 0.006 * scale)
    for sz in (-0.06, 0.06):
        p = sapien.Pose(p=[(hx + front_x) / 2, hy, hz + sz * scale])
        door.add_box_collision(p, standoff_half, material=mat, density=300)
        door.add_box_visual(p, standoff_half, material=metal)
    ab.initial_pose = pose
    return ab.build(name=name, fix_root_link=fixed)


def _rec(id, category, tags, bmin, bmax, mass, friction, build, joints=()):
    return AssetRecord(id=id, category=category, source=PROCEDURAL_SOURCE, licence=PROCEDURAL_LICENCE, tags=tags,
                       bbox_min_m=bmin, bbox_max_m=bmax, mass_kg=mass, friction=friction, build=build,
                       joints=joints)


_dx, _dy, _dz = CABINET_SIZE_M
CATALOG: dict[str, AssetRecord] = {
    r.id: r
    for r in (
        _rec("apple", "fruit", ("graspable", "food", "round"), (-0.04, -0.04, 0.0), (0.04, 0.04, 0.08), 0.15, 1.0,
             build_apple),
        _rec("bowl", "kitchenware", ("container", "tableware"), (-0.088, -0.088, 0.0), (0.088, 0.088, 0.06), 0.3,
             1.0, build_bowl),
        _rec("bottle", "kitchenware", ("graspable", "container"), (-0.033, -0.033, 0.0), (0.033, 0.033, 0.20), 0.3,
             1.0, build_bottle),
        _rec("cabinet", "furniture", ("articulated", "container"), (-_dx / 2 - 0.075, -_dy / 2, 0.0),
             (_dx / 2, _dy / 2, _dz), 8.0, 0.8, build_cabinet,
             joints=(JointRecord("door_hinge", "revolute", (0.0, 1.9), 0.0, 1.4, "door",
                                 (-_dx / 2 - 0.015 - 0.035, -_dy / 2 + 0.06, _dz / 2)),)),
    )
}


def asset_ids() -> tuple[str, ...]:
    return tuple(sorted(CATALOG))


def get_asset(asset_id: str) -> AssetRecord:
    """The record of ``asset_id``; raises :class:`AssetNotFoundError` with suggestions."""
    try:
        return CATALOG[asset_id]
    except KeyError:
        raise AssetNotFoundError(
            f"unknown asset {asset_id!r}.{suggest(asset_id, CATALOG)} Known assets: {', '.join(asset_ids())}"
        ) from None


def lowest_point_z(record: AssetRecord, scale: float, quat_wxyz) -> float:
    """Lowest z (metres) of the asset's scaled bounding box after rotating it by ``quat_wxyz``, in its own frame."""
    lo, hi = np.asarray(record.bbox_min_m) * scale, np.asarray(record.bbox_max_m) * scale
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    rot = sapien.Pose(q=list(quat_wxyz)).to_transformation_matrix()[:3, :3]
    return float((corners @ rot.T)[:, 2].min())
