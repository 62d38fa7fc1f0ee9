"""Helpers shared by the YCB and PartNet-Mobility readers: where ManiSkill keeps its data, asset ids, checked JSON
values, convex-part meshes and the construction of the :class:`AssetEntry` both datasets produce.

Nothing here creates, downloads or writes a file; it only reads what is on disk.
"""

from __future__ import annotations

import importlib.util
import json
import logging
import math
import os
import re
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from gendex_envs.assets.manifest import AssetEntry
from gendex_envs.errors import AssetNotFoundError

log = logging.getLogger(__name__)


# ---------------------------------------------------------------------------------------------- ManiSkill folders
def maniskill_asset_dir() -> Path:
    """ManiSkill's data folder: ``$MS_ASSET_DIR/data``, default ``~/.maniskill/data`` (as ``mani_skill.ASSET_DIR``).

    Computed the same way as ``mani_skill/__init__.py`` without importing ManiSkill; creates nothing.
    """
    return Path(os.path.join(os.getenv("MS_ASSET_DIR", os.path.join(os.path.expanduser("~"), ".maniskill")),
                             "data"))


def _maniskill_package_meta_dir() -> Path | None:
    """``mani_skill/assets/partnet_mobility/meta`` of the installed ManiSkill (found without importing it)."""
    try:
        spec = importlib.util.find_spec("mani_skill")
    except (ImportError, ValueError):
        return None
    if spec is None or not spec.origin:
        return None
    d = Path(spec.origin).parent / "assets" / "partnet_mobility" / "meta"
    return d if d.is_dir() else None


# ---------------------------------------------------------------------------------------------- ids and values
def _snake(text: str) -> str:
    """``StorageFurniture`` -> ``storage_furniture``; ``065-a cups`` -> ``065_a_cups``."""
    text = re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", str(text))
    return re.sub(r"[^a-z0-9]+", "_", text.lower()).strip("_")


def _asset_id(prefix: str, model_id: str) -> str:
    return f"{prefix}_{_snake(model_id)}"


def _load_json(path: Path) -> object:
    try:
        return json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise AssetNotFoundError(f"{path}: cannot read JSON: {exc}") from exc


def _vec3(value: object, where: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float) if isinstance(value, list | tuple) else None
    if arr is None or arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise AssetNotFoundError(f"{where}: expected a list of 3 finite numbers, got {value!r}")
    return arr


def _number(value: object, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) or value <= 0:
        raise AssetNotFoundError(f"{where}: expected a positive number, got {value!r}")
    return float(value)


def _tuple3(a: np.ndarray) -> tuple[float, float, float]:
    return (float(a[0]), float(a[1]), float(a[2]))


# ---------------------------------------------------------------------------------------------- meshes
def _load_parts(path: Path) -> list:
    """The convex parts SAPIEN makes of a collision file: one per ``o`` block of an .obj, one per connected
    component of any other format (what ``add_multiple_convex_collisions_from_file`` does)."""
    import trimesh

    try:
        if path.suffix.lower() == ".obj":
            loaded = trimesh.load(str(path), split_object=True, group_material=False, process=False)
            parts = loaded.dump() if isinstance(loaded, trimesh.Scene) else [loaded]
        else:
            mesh = trimesh.load(str(path), force="mesh", process=False)
            parts = mesh.split(only_watertight=False) if len(mesh.faces) else [mesh]
    except Exception as exc:  # trimesh raises many types for unreadable files
        raise AssetNotFoundError(f"{path}: cannot read mesh: {exc}") from exc
    parts = [p for p in parts if isinstance(p, trimesh.Trimesh) and len(p.vertices)]
    if not parts:
        raise AssetNotFoundError(f"{path}: mesh has no vertices")
    return parts


def _parts_vertices(parts: Iterable) -> np.ndarray:
    """All vertices of some mesh parts, one (n, 3) float array."""
    return np.concatenate([np.asarray(p.vertices, dtype=float) for p in parts])


def _vertices(path: Path) -> np.ndarray:
    return _parts_vertices(_load_parts(path))


def _hull_volume(parts: Iterable) -> float:
    vol = 0.0
    for p in parts:
        try:
            vol += abs(float(p.convex_hull.volume))
        except Exception:  # degenerate (flat) parts have no hull volume
            log.debug("degenerate convex part ignored in volume")
    return vol


def _bounds(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return points.min(axis=0), points.max(axis=0)


# ---------------------------------------------------------------------------------------------- entries
def _grounded(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Bounds raised so that the lowest point is at z = 0, and the raise ``dz`` (the ``origin_dz_m`` param)."""
    dz = -float(lo[2])
    return lo + [0.0, 0.0, dz], hi + [0.0, 0.0, dz], dz


def _dataset_entry(prefix: str, model_id: str, *, tags: Iterable[str], lo: np.ndarray, hi: np.ndarray,
                   mass: float, **fields: object) -> AssetEntry:
    """The :class:`AssetEntry` of one dataset model: id ``<prefix>_<model_id>`` (snake_case), bbox from the
    (grounded) bounds ``lo``/``hi``, mass in kg; ``fields`` are the other :class:`AssetEntry` fields."""
    return AssetEntry(
        id=_asset_id(prefix, model_id),
        tags=tuple(tags),
        bbox_min_m=_tuple3(lo),
        bbox_max_m=_tuple3(hi),
        mass_kg=float(mass),
        **fields,
    )
