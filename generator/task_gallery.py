"""The task gallery: ``docs/tasks.md``, one row per task with its picture, written by ``gendex tasks-doc``.

Each row: a thumbnail of the task at reset (seed 0, the left-overhead view, rendered by the task's own env), the
Gymnasium id, the instruction, its task skills (:func:`generator.stats.task_skills`), objects, stages, and what the
solvability gate measured (success and env steps per success; "—" for a task that has no gate record).
"""

from __future__ import annotations

import logging
import re
import shutil
from collections import Counter
from collections.abc import Mapping
from pathlib import Path

from gymnasium import error as gym_error
from gymnasium.envs.registration import parse_env_id
from PIL import Image
from tqdm import tqdm

from gendex_envs.task_version import TaskVersion
from generator.stats import latest_versions, task_skills

log = logging.getLogger(__name__)

THUMB_PX = 192


def thumbnail(version: TaskVersion, size: int = THUMB_PX):
    """[size, size, 3] uint8: the task at reset (seed 0), left-overhead view."""
    from gendex_envs.registry import make_task_env

    env = make_task_env(version, render_mode="rgb_array", render_backend="cpu", view_resolution=size)
    try:
        env.reset(seed=0)
        return env.render_views(("left_overhead",))["left_overhead"][0]
    finally:
        env.close()


def _row(env_id: str, version: TaskVersion, picture: str) -> str:
    spec = version.spec
    gate = version.provenance().get("solvability")
    measured = "—" if gate is None else f"{gate['successes']}/{gate['attempts']}"
    per = "—" if not gate or not gate.get("env_steps_per_success") else f"{gate['env_steps_per_success']:.0f}"
    skills = ", ".join(task_skills(spec)) or "—"
    counts = Counter(o.asset for o in spec.objects)  # a dozen beads: `bead` x 12
    objects = ", ".join(f"`{a}`" + (f" × {n}" if n > 1 else "") for a, n in counts.items())
    stages = " → ".join(s.skill for s in spec.stages)
    return (f"| ![{version.name}]({picture}) | `{env_id}` | {spec.instruction} | {skills} | {objects} | {stages} | "
            f"{measured} | {per} |")


def _picture_of_source(version: TaskVersion, pictures: Path) -> Path | None:
    """Where the picture of the version ``version`` was reworded from would be (None: not a rewording, or a record
    whose source is no versioned task id: the folder is untrusted, its picture is then drawn)."""
    source = (version.provenance().get("reword") or {}).get("source")
    try:
        _, name, number = parse_env_id(source) if isinstance(source, str) else (None, None, None)
    except gym_error.Error:
        return None
    return pictures / f"{name}-v{number}.png" if name and number is not None else None


def write_task_gallery(versions: Mapping[str, TaskVersion], out: Path, pictures: Path | None = None,
                       all_versions: bool = False, size: int = THUMB_PX, rerender: bool = False) -> Path:
    """Write the gallery Markdown to ``out`` and a thumbnail per task into ``pictures`` (default: a folder named
    after ``out`` beside it); returns ``out``. A version's folder never changes once published, so a picture already
    there of that version and size is kept; ``rerender`` draws every one again (after a change to the renderer or to
    an asset). A reworded version (its scene byte for byte its source's) takes its source's picture. Pictures of
    versions the gallery no longer shows are removed."""
    chosen = dict(versions) if all_versions else latest_versions(versions)
    pictures = pictures or out.with_suffix("")
    pictures.mkdir(parents=True, exist_ok=True)
    rows = []

    def fits(png: Path) -> bool:
        return not rerender and png.is_file() and Image.open(png).size == (size, size)

    for env_id, version in tqdm(sorted(chosen.items()), desc="task pictures", unit="task"):
        png = pictures / f"{version.name}-v{version.version}.png"
        if not fits(png):
            source = _picture_of_source(version, pictures)
            if source is not None and fits(source):
                shutil.copyfile(source, png)
            else:
                Image.fromarray(thumbnail(version, size)).save(png)
        rows.append(_row(env_id, version, png.relative_to(out.parent).as_posix()))
    shown = {f"{v.name}-v{v.version}.png" for v in chosen.values()}
    stale = [p for p in pictures.glob("*.png") if re.fullmatch(r"\w+-v\d+\.png", p.name) and p.name not in shown]
    for p in stale:
        p.unlink()
    head = ["# Task library", "",
            f"{len(rows)} tasks ({'every version' if all_versions else 'the latest version of each'}), written by "
            "`gendex tasks-doc`. Picture: the task at reset (seed 0). *Solved*: the version's solvability record "
            "(successes / attempts of the stage executor on the task's own unseen seeds; the gate stops after 3 "
            "failures of 10), written when the task was generated or by `gendex gate --write`; — where there is "
            "none. The larger measurements are in [solving](solving.md); `gendex stats` gives the numbers over "
            "the library.", "",
            "| picture | task | instruction | skills | objects | stages | solved | env steps / success |",
            "|---|---|---|---|---|---|---|---|"]
    out.write_text("\n".join(head + rows) + "\n")
    log.info("wrote %s (%d tasks)", out, len(rows))
    return out


__all__ = ["thumbnail", "write_task_gallery"]
