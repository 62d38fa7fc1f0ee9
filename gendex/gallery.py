"""The asset gallery: a thumbnail of every catalog asset, rendered by GenDex's own env, and a Markdown index."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
from mani_skill.utils import sapien_utils
from PIL import Image
from tqdm import tqdm

from gendex_envs.assets.catalog import AssetRecord, catalog
from gendex_envs.atomic_io import atomic_path, write_text
from gendex_envs.spec import parse_task_spec

log = logging.getLogger(__name__)

FRONT_X_M = 0.32
"""Each asset stands with its front (its -x face) here: in front of the robot, clear of the hand."""


def _spot(record: AssetRecord) -> tuple[float, float]:
    return FRONT_X_M - record.bbox_min_m[0], 0.0


def _spec(record: AssetRecord):
    x, y = _spot(record)
    return parse_task_spec({
        "name": "Gallery",
        "instruction": f"Look at the {record.category}.",
        "objects": [{"name": "item", "asset": record.id, "pos_m": [x, y, 0.0],
                     "fixed": record.articulated}],
        "stages": [{"name": "look", "instruction": "Nothing to do.", "skill": "reach", "method": "RL",
                    "control_joint": "hand", "target": "item"}],
        "success": {"description": "never", "conditions": [{"type": "lifted", "object": "item",
                                                             "min_height_m": 10.0}]},
    }, source=f"<gallery:{record.id}>")


def render_thumbnail(record: AssetRecord, size: int = 256) -> np.ndarray:
    """[size, size, 3] uint8 close-up of ``record`` standing on the task table."""
    from gendex_envs.task_env import TaskEnv

    extent = max(max(record.size_m), 0.06)
    x, y = _spot(record)
    centre = [x + (record.bbox_min_m[0] + record.bbox_max_m[0]) / 2, y, record.size_m[2] / 2]
    d = 1.6 * extent + 0.12
    eye = [centre[0] - 0.75 * d, centre[1] - 0.75 * d, centre[2] + 0.7 * d]
    cameras = {"left_overhead": {"pose": sapien_utils.look_at(eye, centre), "width": size, "height": size,
                                 "fov": 0.8}}
    env = TaskEnv(task_spec=_spec(record), render_mode="rgb_array", render_backend="cpu",
                  human_render_camera_configs=cameras)
    try:
        env.reset(seed=0)
        return env.render_views(("left_overhead",))["left_overhead"][0]
    finally:
        env.close()


def render_gallery(out: Path, size: int = 256, rerender: bool = True, held: dict[str, str] | None = None) -> Path:
    """Write ``out/<id>.png`` for every asset (``rerender=False``: only those not there yet) and the index
    ``out.md``, rigid objects and articulated models in two tables by category; ``held``: what the *held* column
    says of each rigid object (how the solver holds it); returns the index path."""
    held = held or {}
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    records = sorted(catalog().values(), key=lambda r: (r.articulated, r.category, r.id))
    rows: dict[bool, list[str]] = {False: [], True: []}
    for record in tqdm(records, desc="gallery", unit="asset"):
        png = out / f"{record.id}.png"
        if rerender or not png.is_file():
            with atomic_path(png) as tmp:
                Image.fromarray(render_thumbnail(record, size)).save(tmp)
        size_cm = " × ".join(f"{100 * v:.1f}" for v in record.size_m)
        last = (", ".join(f"{j.name} ({j.type})" for j in record.joints) if record.articulated
                else held.get(record.id, "—"))
        rows[record.articulated].append(
            f"| ![{record.id}]({out.name}/{png.name}) | `{record.id}` | {record.category} | {size_cm} | "
            f"{record.mass_kg:.3g} | {last} | {', '.join(record.tags)} | {record.entry.licence} |")
    rigid = [r for r in records if not r.articulated]
    arts = [r for r in records if r.articulated]
    index = out.with_suffix(".md")
    text = [
        "# Asset gallery",
        "",
        f"{len(records)} assets: {len(rigid)} rigid objects in {len({r.category for r in rigid})} categories and "
        f"{len(arts)} articulated models in {len({r.category for r in arts})} categories, each rendered on the task "
        "table by `gendex gallery` (the project's own env; the ShadowHand may appear at the edge for scale). Sizes are "
        "real-world at scale 1. *Held* is the solver's lift-and-hold record (`benchmarks/grasp.py`, "
        "`gendex/solve/grasp_measured.json`): the offline author grasps only objects held in at least 90 % of it.",
        "",
        "## Rigid objects",
        "",
        "| view | id | category | size cm (x × y × z) | mass kg | held | tags | licence |",
        "|---|---|---|---|---|---|---|---|",
        *rows[False],
        "",
        "## Articulated models",
        "",
        "| view | id | category | size cm (x × y × z) | mass kg | joints | tags | licence |",
        "|---|---|---|---|---|---|---|---|",
        *rows[True],
    ]
    write_text(index, "\n".join(text) + "\n")
    return index
