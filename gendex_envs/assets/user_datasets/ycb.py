"""YCB objects from ManiSkill's asset directory, as rigid :class:`AssetEntry` objects.

Layout read (``<data>`` is :func:`~gendex_envs.assets.user_datasets.common.maniskill_asset_dir`)::

    <data>/assets/mani_skill2_ycb/info_pick_v0.json          # {model_id: {"bbox": {"min", "max"}, "scales", "density"}}
    <data>/assets/mani_skill2_ycb/models/<model_id>/textured.obj     # visual
    <data>/assets/mani_skill2_ycb/models/<model_id>/collision.ply    # convex parts (collision.obj also accepted)

Units and frames (``file_scale``, ``origin_dz_m``): see :mod:`gendex_envs.assets.user_datasets`.
"""

from __future__ import annotations

import logging
import re
from pathlib import Path

import numpy as np

from gendex_envs.assets.manifest import AssetEntry
from gendex_envs.assets.user_datasets.common import (
    _bounds,
    _dataset_entry,
    _grounded,
    _hull_volume,
    _load_json,
    _load_parts,
    _number,
    _parts_vertices,
    _snake,
    _vec3,
    maniskill_asset_dir,
)
from gendex_envs.errors import AssetNotFoundError

log = logging.getLogger(__name__)

# ---------------------------------------------------------------------------------------------- layout constants
YCB_DIR = Path("assets") / "mani_skill2_ycb"
"""mani_skill/utils/assets/data.py: DATA_SOURCES["ycb"].target_path = "assets/mani_skill2_ycb"."""
YCB_INFO = "info_pick_v0.json"
"""mani_skill/utils/building/actors/ycb.py: load_json(ASSET_DIR / "assets/mani_skill2_ycb/info_pick_v0.json")."""
YCB_MODELS = "models"
YCB_VISUAL = "textured.obj"
YCB_COLLISIONS = ("collision.ply", "collision.obj")
"""ycb.py reads models/<id>/collision.ply and models/<id>/textured.obj; collision.obj is accepted as well."""
YCB_SOURCE = "YCB via ManiSkill asset dir"
YCB_LICENCE = "CC-BY-4.0 (YCB)"
YCB_DEFAULT_DENSITY = 1000.0
"""ycb.py: density = metadata.get("density", 1000)."""
YCB_FRICTION = 0.8
"""Static friction given to YCB objects (ManiSkill leaves the scene default of 0.3; household objects are higher)."""
YCB_HARD_TO_GRASP = frozenset({"022_windex_bottle", "028_skillet_lid", "029_plate", "059_chain"})
"""pick_single_ycb.py excludes these as non-graspable / hard to grasp; they do not get the ``graspable`` tag."""

# YCB id token -> tags (tokens of the category, e.g. "tomato_soup_can" -> tomato, soup, can)
_FRUIT = ("banana", "strawberry", "apple", "lemon", "peach", "pear", "orange", "plum")
_YCB_TAGS: dict[str, tuple[str, ...]] = {
    **{k: ("fruit", "food") for k in _FRUIT},
    **{k: ("food",) for k in ("chips", "chef", "soup", "mustard", "tuna", "pudding", "gelatin", "meat", "sugar",
                              "cracker")},
    "box": ("box",),
    "brick": ("box",),
    "bottle": ("container",),
    **{k: ("kitchenware", "tableware", "container") for k in ("bowl", "mug", "cups", "pitcher")},
    **{k: ("kitchenware", "tableware") for k in ("plate",)},
    "skillet": ("kitchenware",),
    **{k: ("kitchenware", "utensil") for k in ("fork", "spoon", "knife", "spatula")},
    **{k: ("tool",) for k in ("drill", "scissors", "marker", "wrench", "screwdriver", "hammer", "clamp", "padlock")},
    **{k: ("ball",) for k in ("ball", "softball", "baseball", "marbles")},
    **{k: ("toy",) for k in ("block", "blocks", "dice", "cube", "lego", "duplo", "airplane", "peg")},
    **{k: ("household",) for k in ("sponge", "cleanser", "chain")},
}


def ycb_category(model_id: str) -> str:
    """Noun of a YCB model id: ``002_master_chef_can`` -> ``master_chef_can``, ``065-a_cups`` -> ``cups``."""
    noun = re.sub(r"^\d+(-[a-z])?_", "", model_id.strip())
    return _snake(noun) or _snake(model_id)


def ycb_tags(model_id: str) -> tuple[str, ...]:
    tags: list[str] = [] if model_id in YCB_HARD_TO_GRASP else ["graspable"]
    for token in ycb_category(model_id).split("_"):
        for t in _YCB_TAGS.get(token, ()):
            if t not in tags:
                tags.append(t)
    return tuple(tags)


def _ycb_dir(root: Path | None) -> Path:
    return (Path(root) if root is not None else maniskill_asset_dir()) / YCB_DIR


def _ycb_metadata(info_path: Path) -> dict[str, dict]:
    raw = _load_json(info_path)
    if not isinstance(raw, dict):
        raise AssetNotFoundError(f"{info_path}: expected a JSON object mapping model ids to metadata")
    for model_id, meta in raw.items():
        if not isinstance(meta, dict):
            raise AssetNotFoundError(f"{info_path}: {model_id!r}: expected an object, got {type(meta).__name__}")
        if "bbox" in meta:
            bbox = meta["bbox"]
            if not isinstance(bbox, dict) or "min" not in bbox or "max" not in bbox:
                raise AssetNotFoundError(f"{info_path}: {model_id!r}.bbox: expected {{'min': [x,y,z], 'max': [x,y,z]}}")
            lo = _vec3(bbox["min"], f"{info_path}: {model_id!r}.bbox.min")
            hi = _vec3(bbox["max"], f"{info_path}: {model_id!r}.bbox.max")
            if np.any(hi < lo):
                raise AssetNotFoundError(f"{info_path}: {model_id!r}.bbox: max < min")
        if "scales" in meta:
            scales = meta["scales"]
            if not isinstance(scales, list) or not scales:
                raise AssetNotFoundError(f"{info_path}: {model_id!r}.scales: expected a non-empty list")
            _number(scales[0], f"{info_path}: {model_id!r}.scales[0]")
        if "density" in meta:
            _number(meta["density"], f"{info_path}: {model_id!r}.density")
    return raw


def _ycb_entry(model_id: str, meta: dict, model_dir: Path) -> AssetEntry | None:
    visual = model_dir / YCB_VISUAL
    collision = next((model_dir / c for c in YCB_COLLISIONS if (model_dir / c).is_file()), None)
    if collision is None or not visual.is_file():
        log.debug("YCB %s skipped: %s or %s missing in %s", model_id, YCB_VISUAL, "/".join(YCB_COLLISIONS),
                  model_dir)
        return None
    scale = float(meta.get("scales", [1.0])[0])
    density = float(meta.get("density", YCB_DEFAULT_DENSITY))
    parts = _load_parts(collision)
    if "bbox" in meta:
        lo = np.asarray(meta["bbox"]["min"], dtype=float) * scale
        hi = np.asarray(meta["bbox"]["max"], dtype=float) * scale
    else:
        lo, hi = _bounds(_parts_vertices(parts) * scale)
    lo, hi, dz = _grounded(lo, hi)
    volume = _hull_volume(parts) * scale**3
    mass = density * volume if volume > 0 else density * float(np.prod(hi - lo))
    return _dataset_entry(
        "ycb", model_id,
        category=ycb_category(model_id),
        kind="rigid",
        source=YCB_SOURCE,
        licence=YCB_LICENCE,
        tags=ycb_tags(model_id),
        lo=lo,
        hi=hi,
        mass=mass,
        friction=YCB_FRICTION,
        visual=str(visual.resolve()),
        collision=str(collision.resolve()),
        volume_m3=float(volume) if volume > 0 else None,
        params={"origin_dz_m": dz, "file_scale": scale, "density_kg_m3": density, "model_id": model_id},
    )


def load_ycb(root: Path | None = None) -> list[AssetEntry]:
    """YCB models present under ``root`` (ManiSkill's data folder; default :func:`maniskill_asset_dir`).

    Model ids come from ``info_pick_v0.json`` (as in ManiSkill); entries whose files are missing are skipped. Without
    the json, every ``models/<id>/`` folder with both files is read, its bbox taken from the collision mesh.
    """
    ycb = _ycb_dir(root)
    info_path = ycb / YCB_INFO
    models = ycb / YCB_MODELS
    if info_path.is_file():
        metadata = _ycb_metadata(info_path)
    elif models.is_dir():
        log.debug("%s missing: reading every model folder in %s", info_path, models)
        metadata = {d.name: {} for d in models.iterdir() if d.is_dir()}
    else:
        log.debug("no YCB data at %s", ycb)
        return []
    entries = []
    for model_id in sorted(metadata):
        entry = _ycb_entry(model_id, metadata[model_id], models / model_id)
        if entry is not None:
            entries.append(entry)
    log.debug("YCB: %d of %d models found in %s", len(entries), len(metadata), ycb)
    return entries
