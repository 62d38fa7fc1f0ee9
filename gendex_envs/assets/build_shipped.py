"""Import licence-clean textured meshes shipped in installed packages (`python -m gendex_envs.assets.build_shipped`).

Each source mesh is turned into the GenDex asset frame (z up, origin at the bottom centre), scaled to its real-world
size, and written as ``<id>/visual.glb`` (textures kept) plus ``<id>/collision.obj`` (its convex hull: only convex-ish
sources are imported, so no decomposition is needed). The result is committed; envs only load it.
"""

from __future__ import annotations

import argparse
import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from gendex_envs.assets.build_objects import _obj_block
from gendex_envs.assets.manifest import DATA_DIR, MANIFEST, AssetEntry, write_manifest

log = logging.getLogger(__name__)

DEFAULT_OUT = DATA_DIR / "shipped"
Y_UP_TO_Z_UP = trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0])


@dataclass(frozen=True)
class ShippedMesh:
    id: str
    category: str
    package: str
    path: str
    """File inside the installed package."""
    licence: str
    up: str
    """"y" or "z": the source's up axis."""
    size_axis: int
    size_m: float
    """Real-world extent along ``size_axis`` of the asset frame; the mesh is scaled uniformly to it."""
    mass_kg: float
    friction: float
    tags: tuple[str, ...]


SOURCES = (
    ShippedMesh("apple_scan", "apple", "mani_skill", "envs/tasks/humanoid/assets/apple_1.glb", "Apache-2.0 (ManiSkill)",
                "y", 0, 0.08, 0.16, 0.9, ("graspable", "food", "fruit", "textured")),
)

LICENCE_TEXT = """Meshes in this folder are converted by GenDex (python -m gendex_envs.assets.build_shipped) from files
that ship inside installed Python packages, under the licences recorded per asset in manifest.json:

- apple_scan: ManiSkill 3 (mani_skill/envs/tasks/humanoid/assets/apple_1.glb), Apache License 2.0,
  Copyright the ManiSkill authors (Hillbot Inc. / UC San Diego SU Lab).

The conversion (rotation to z up, uniform scaling to real size, convex-hull collision) is Apache-2.0 like GenDex.
"""


def _source_file(src: ShippedMesh) -> Path:
    import importlib

    return Path(importlib.import_module(src.package).__file__).parent / src.path


def convert(src: ShippedMesh, out: Path) -> AssetEntry:
    scene = trimesh.load(_source_file(src), force="scene")
    if src.up == "y":
        scene.apply_transform(Y_UP_TO_Z_UP)
    lo, hi = scene.bounds
    scale = src.size_m / (hi - lo)[src.size_axis]
    centre = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]])
    tf = trimesh.transformations
    scene.apply_transform(tf.scale_matrix(scale) @ tf.translation_matrix(-centre))
    folder = out / src.id
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "visual.glb").write_bytes(scene.export(file_type="glb"))
    hull = scene.to_geometry().convex_hull
    hull.vertices = np.round(hull.vertices, 6)
    header = f"# convex hull of {src.package}/{src.path}\n"
    (folder / "collision.obj").write_text(header + _obj_block(hull, "hull_0", 1))
    lo, hi = scene.bounds
    return AssetEntry(
        id=src.id, category=src.category, kind="rigid", source=f"{src.package} package: {src.path}",
        licence=src.licence, tags=src.tags, bbox_min_m=tuple(round(float(v), 6) for v in lo),
        bbox_max_m=tuple(round(float(v), 6) for v in hi), mass_kg=src.mass_kg, friction=src.friction,
        visual=f"{src.id}/visual.glb", collision=f"{src.id}/collision.obj", volume_m3=round(float(hull.volume), 9),
        rgba=(1.0, 1.0, 1.0, 1.0), params={"source_scale": round(float(scale), 6)},
    )


def build(out: Path = DEFAULT_OUT) -> list[AssetEntry]:
    out = Path(out)
    entries = [convert(src, out) for src in SOURCES]
    (out / "LICENSE").write_text(LICENCE_TEXT)
    write_manifest(out / MANIFEST, entries, note="Textured meshes converted from installed packages "
                                                 "(python -m gendex_envs.assets.build_shipped).")
    log.info("wrote %d shipped assets to %s", len(entries), out)
    return entries


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO)
    build(args.out)


if __name__ == "__main__":
    main()
