"""The asset catalog: one typed :class:`AssetRecord` per asset a task YAML may reference.

Records come from the manifests shipped in ``gendex_envs/assets/data/*/manifest.json`` (procedural objects and
articulated models, generated once and committed) and, when present on disk, from user-supplied YCB and
PartNet-Mobility data in ManiSkill's asset directory (:mod:`gendex_envs.assets.user_datasets`). Nothing is
downloaded and no convex decomposition is computed at run time: rigid assets load their committed hull files.

Frame convention (see :mod:`gendex_envs.assets.manifest`): z up, origin on the footprint centre at the lowest point
of the asset in its rest pose; sizes are real-world metres at scale 1.
"""

from __future__ import annotations

import functools
import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import sapien

from gendex_envs.assets.manifest import AssetEntry, JointEntry, read_manifest, shipped_manifests
from gendex_envs.errors import AssetNotFoundError, suggest
from gendex_envs.physx import px_bodies

log = logging.getLogger(__name__)

DYNAMIC_FRICTION_RATIO = 0.8
THIN_M = 0.015
"""An object whose thinnest side (at the scale it is built) is under this is *thin*: a knife, a spoon, a fork."""
THIN_SOLVER_ITERATIONS = 40
"""Contact-solver position iterations of a thin object's body (the scene's default is 15). A thin object is held by
fingertip pads that meet it over a few millimetres, nearly edge-on; at 15 iterations PhysX leaves that friction
unconverged and a knife turns out of the pads as it rises. PhysX solves an island at the largest count of its
bodies, so this costs only while the object touches something that moves; no other object's contacts change."""


@dataclass(frozen=True)
class AssetRecord:
    """An asset of the catalog: its manifest entry and where its files are."""

    entry: AssetEntry
    root: Path
    """Folder that the entry's relative file paths are relative to."""

    # ------------------------------------------------------------------ facts
    @property
    def id(self) -> str:
        return self.entry.id

    @property
    def category(self) -> str:
        return self.entry.category

    @property
    def tags(self) -> tuple[str, ...]:
        return self.entry.tags

    @property
    def articulated(self) -> bool:
        return self.entry.kind == "articulated"

    @property
    def joints(self) -> tuple[JointEntry, ...]:
        return self.entry.joints

    @property
    def bbox_min_m(self) -> tuple[float, float, float]:
        return self.entry.bbox_min_m

    @property
    def bbox_max_m(self) -> tuple[float, float, float]:
        return self.entry.bbox_max_m

    @property
    def size_m(self) -> tuple[float, float, float]:
        """Bounding-box size (x, y, z) at scale 1, metres."""
        return self.entry.size_m

    @property
    def mass_kg(self) -> float:
        return self.entry.mass_kg

    @property
    def friction(self) -> float:
        return self.entry.friction

    def joint(self, name: str) -> JointEntry:
        for j in self.entry.joints:
            if j.name == name:
                return j
        names = [j.name for j in self.entry.joints]
        raise AssetNotFoundError(f"asset {self.id!r} has no joint {name!r}; joints: {names}.{suggest(name, names)}")

    def path(self, rel: str) -> Path:
        p = Path(rel)
        return p if p.is_absolute() else self.root / p

    @property
    def origin_dz_m(self) -> float:
        """How far the (file-scaled) geometry must be raised to put its lowest point at z = 0 (user datasets)."""
        return float(self.entry.params.get("origin_dz_m", 0.0))

    @property
    def file_scale(self) -> float:
        """Scale that turns the stored files into metres at catalog scale 1 (user datasets; 1 for shipped files)."""
        return float(self.entry.params.get("file_scale", 1.0))

    # ------------------------------------------------------------------ building
    def build(self, scene, name: str, scale: float, rgba, fixed: bool, pose: sapien.Pose):
        """Build into a ManiSkill scene: an ``Actor`` (fixed: kinematic) or an ``Articulation`` (fixed: fixed root)."""
        if self.articulated:
            return self._build_articulation(scene, name, scale, fixed, pose)
        return self._build_actor(scene, name, scale, rgba, fixed, pose)

    def solver_position_iterations(self, scale: float) -> int | None:
        """The contact-solver iterations this rigid object's body gets at ``scale``: :data:`THIN_SOLVER_ITERATIONS`
        when it is thin (:data:`THIN_M`), else ``None`` (the scene's default)."""
        if self.articulated:
            return None
        return THIN_SOLVER_ITERATIONS if min(self.size_m) * scale < THIN_M else None

    def _material(self):
        f = self.entry.friction
        return sapien.physx.PhysxMaterial(static_friction=f, dynamic_friction=DYNAMIC_FRICTION_RATIO * f,
                                          restitution=0.0)

    def _build_actor(self, scene, name: str, scale: float, rgba, fixed: bool, pose: sapien.Pose):
        e = self.entry
        s = (scale * self.file_scale,) * 3
        offset = sapien.Pose(p=[0.0, 0.0, self.origin_dz_m * scale])
        density = e.mass_kg / e.volume_m3 if e.volume_m3 else 500.0  # uniform scaling keeps density
        b = scene.create_actor_builder()
        radius = e.params.get("radius_m") if "pourable" in e.tags else None
        if radius:  # a bead: a true sphere, which rolls and stacks in a pile without the jitter of a faceted hull
            r = float(radius) * scale * self.file_scale
            solid = e.mass_kg / (4.0 / 3.0 * np.pi * float(radius) ** 3)
            b.add_sphere_collision(pose=sapien.Pose(p=[0.0, 0.0, self.origin_dz_m * scale + r]), radius=r,
                                   material=self._material(), density=solid)
        else:
            b.add_multiple_convex_collisions_from_file(str(self.path(e.collision)), pose=offset, scale=s,
                                                       material=self._material(), density=density)
        textured = e.visual.endswith((".glb", ".gltf"))  # keep the file's own materials unless a colour is asked for
        look = None if textured and rgba is None else sapien.render.RenderMaterial(base_color=list(rgba or e.rgba),
                                                                                    roughness=0.6)
        b.add_visual_from_file(str(self.path(e.visual)), pose=offset, scale=s, material=look)
        b.initial_pose = pose
        if fixed:
            return b.build_kinematic(name)
        actor = b.build(name)
        iterations = self.solver_position_iterations(scale)
        if iterations is not None:
            for body in px_bodies(actor):
                body.solver_position_iterations = iterations
        return actor

    def _build_articulation(self, scene, name: str, scale: float, fixed: bool, pose: sapien.Pose):
        loader = scene.create_urdf_loader()
        loader.name = name
        loader.fix_root_link = fixed
        loader.scale = scale * self.file_scale
        loader.load_multiple_collisions_from_file = True  # one convex hull per `o` block, as ManiSkill loads them
        loader.set_material(self.entry.friction, DYNAMIC_FRICTION_RATIO * self.entry.friction, 0.0)
        builder = loader.parse(str(self.path(self.entry.urdf)))["articulation_builders"][0]
        builder.initial_pose = pose * sapien.Pose(p=[0.0, 0.0, self.origin_dz_m * scale])
        return builder.build(name=name, fix_root_link=fixed)


@functools.lru_cache(maxsize=1)
def catalog() -> dict[str, AssetRecord]:
    """Every known asset by id: shipped manifests, then user datasets found on disk (ids must be unique)."""
    from gendex_envs.assets.user_datasets import user_dataset_entries

    records: dict[str, AssetRecord] = {}

    def add(entry: AssetEntry, root: Path) -> None:
        if entry.id in records:
            raise AssetNotFoundError(f"asset id {entry.id!r} is defined twice ({records[entry.id].root}, {root})")
        records[entry.id] = AssetRecord(entry, root)

    for manifest in shipped_manifests():
        for entry in read_manifest(manifest):
            add(entry, manifest.parent)
    user = user_dataset_entries()
    for entry in user:
        add(entry, Path("/"))
    log.debug("asset catalog: %d shipped, %d user-supplied", len(records) - len(user), len(user))
    return records


def asset_ids() -> tuple[str, ...]:
    return tuple(sorted(catalog()))


def get_asset(asset_id: str) -> AssetRecord:
    """The record of ``asset_id``; raises :class:`AssetNotFoundError` with suggestions."""
    try:
        return catalog()[asset_id]
    except KeyError:
        raise AssetNotFoundError(
            f"unknown asset {asset_id!r}.{suggest(asset_id, catalog())} List them with `gendex assets`."
        ) from None


def lowest_point_z(record: AssetRecord, scale: float, quat_wxyz) -> float:
    """Lowest z (metres) of the asset's scaled bounding box after rotating it by ``quat_wxyz``, in its own frame."""
    lo, hi = np.asarray(record.bbox_min_m) * scale, np.asarray(record.bbox_max_m) * scale
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    rot = sapien.Pose(q=list(quat_wxyz)).to_transformation_matrix()[:3, :3]
    return float((corners @ rot.T)[:, 2].min())
