"""User-supplied YCB and PartNet-Mobility data, read from ManiSkill's asset directory into :class:`AssetEntry` form.

GenDex never downloads these datasets. Users who already have them (ManiSkill downloads them with
``python -m mani_skill.utils.download_asset ycb`` / ``partnet_mobility_cabinet`` ...) get them in the catalog too.
Nothing here creates, downloads or writes a file; it only reads what is on disk.

Layout read (as ManiSkill 3.0.1 lays it out and reads it; ``<data>`` is :func:`maniskill_asset_dir`)::

    <data>/assets/mani_skill2_ycb/info_pick_v0.json          # {model_id: {"bbox": {"min", "max"}, "scales", "density"}}
    <data>/assets/mani_skill2_ycb/models/<model_id>/textured.obj     # visual
    <data>/assets/mani_skill2_ycb/models/<model_id>/collision.ply    # convex parts (collision.obj also accepted)
    <data>/partnet_mobility/dataset/<model_id>/mobility_cvx.urdf     # or mobility_fixed.urdf, or mobility.urdf
    <data>/partnet_mobility/meta/info_*_train.json           # optional, user-supplied metadata (same format as below)
    mani_skill/assets/partnet_mobility/meta/info_*_train.json    # shipped with ManiSkill: {model_id: {"scale", ...}}

Units and frames of the entries made here (the manifest convention, see :mod:`gendex_envs.assets.manifest`):
the files are *not* rewritten, so each entry carries two ``params`` the catalog must apply when it loads them:

* ``params["file_scale"]``: the dataset's own scale (YCB ``scales[0]``, PartNet-Mobility ``scale``, as ManiSkill
  passes them to its builders); the files must be loaded at ``file_scale x`` the user's scale. Every metric value
  of the entry (bbox, volume, mass, prismatic limits, handle points, ``origin_dz_m``) is already at ``file_scale``,
  i.e. real-world metres at GenDex scale 1.
* ``params["origin_dz_m"]``: how far (metres, at GenDex scale 1) the loaded geometry must be raised so that its
  lowest point is at z = 0. ``bbox_min_m`` z is therefore 0. x/y are left as the dataset has them (YCB and
  ManiSkill's PartNet-Mobility models are centred near the origin; the bbox records the exact extent).

Modules: :mod:`~gendex_envs.assets.user_datasets.common` (ManiSkill folders, ids, meshes, entry construction),
:mod:`~gendex_envs.assets.user_datasets.ycb` and :mod:`~gendex_envs.assets.user_datasets.partnet_mobility`.
"""

from __future__ import annotations

import logging
from pathlib import Path

from gendex_envs.assets.manifest import AssetEntry
from gendex_envs.assets.user_datasets.common import maniskill_asset_dir
from gendex_envs.assets.user_datasets.partnet_mobility import (
    PM_CONTAINERS,
    PM_DEFAULT_DENSITY,
    PM_DIR,
    PM_FRICTION,
    PM_LICENCE,
    PM_META_CATEGORY,
    PM_OPEN_FRACTION,
    PM_PRIORITY_LABELS,
    PM_SOURCE,
    PM_URDF_NAMES,
    PM_USER_META_DIR,
    load_partnet_mobility,
)
from gendex_envs.assets.user_datasets.ycb import (
    YCB_COLLISIONS,
    YCB_DEFAULT_DENSITY,
    YCB_DIR,
    YCB_FRICTION,
    YCB_HARD_TO_GRASP,
    YCB_INFO,
    YCB_LICENCE,
    YCB_MODELS,
    YCB_SOURCE,
    YCB_VISUAL,
    load_ycb,
    ycb_category,
    ycb_tags,
)

log = logging.getLogger(__name__)

__all__ = [
    "PM_CONTAINERS", "PM_DEFAULT_DENSITY", "PM_DIR", "PM_FRICTION", "PM_LICENCE", "PM_META_CATEGORY",
    "PM_OPEN_FRACTION", "PM_PRIORITY_LABELS", "PM_SOURCE", "PM_URDF_NAMES", "PM_USER_META_DIR",
    "YCB_COLLISIONS", "YCB_DEFAULT_DENSITY", "YCB_DIR", "YCB_FRICTION", "YCB_HARD_TO_GRASP", "YCB_INFO",
    "YCB_LICENCE", "YCB_MODELS", "YCB_SOURCE", "YCB_VISUAL",
    "load_partnet_mobility", "load_ycb", "maniskill_asset_dir", "user_dataset_entries", "ycb_category", "ycb_tags",
]


def user_dataset_entries(root: Path | None = None) -> list[AssetEntry]:
    """Every YCB and PartNet-Mobility entry found under ``root`` (default :func:`maniskill_asset_dir`); [] if none."""
    root = Path(root) if root is not None else maniskill_asset_dir()
    if not root.is_dir():
        log.debug("ManiSkill asset folder %s does not exist: no user datasets", root)
        return []
    return load_ycb(root) + load_partnet_mobility(root)
