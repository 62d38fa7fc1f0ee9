"""The main job's task pass (``gendex demo``): the newest version of each task is built once, its three views are
rendered at reset and saved, random actions are rolled out, and the left-overhead views of all tasks are laid out as
one contact sheet.

Older versions of a task are mostly rewordings of the same scene; rendering them too tripled the run and its output
without showing anything new (``benchmarks/results/demo.md``).
"""

from __future__ import annotations

import logging
import math
import re
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont
from tqdm import tqdm

from gendex_envs.atomic_io import atomic_path
from gendex_envs.task_version import TaskVersion
from generator.stats import latest_versions, task_skills

log = logging.getLogger(__name__)

SHEET_VIEW = "left_overhead"
"""The view each task shows on the contact sheet (the one ``docs/tasks.md`` shows)."""
TILE_PX = 192
"""Side of a contact-sheet tile, pixels: 86 tiles at 192 px make a sheet of about 0.4 MB."""
MARGIN_PX = 2
"""White border around each tile and its label."""
LABEL_FONT_PX = 11
"""Height of the label font, pixels."""


@dataclass(frozen=True)
class DemoRow:
    """What the demo measured on one task version."""

    env_id: str
    """Gymnasium id, ``GenDex/<Name>-v<N>``."""
    skills: tuple[str, ...]
    """The task skills it exercises (:func:`generator.stats.task_skills`)."""
    steps: int
    """Random control steps rolled out."""
    steps_per_s: float
    """Control steps per second of wall time over the rollout (env build and rendering excluded)."""
    rewards_finite: bool
    """Every reward of the rollout was finite."""
    mean_reward: float
    """Mean reward over the rollout."""
    success: bool
    """The task's success held at some step of the random rollout."""


def demo_versions(versions: Mapping[str, TaskVersion]) -> list[TaskVersion]:
    """The versions the demo runs: the highest version of each task name, sorted by name."""
    return sorted(latest_versions(versions).values(), key=lambda v: v.name)


def _words(label: str) -> list[str]:
    """``CloseDrawerChest2-v1`` -> ``["Close", "Drawer", "Chest2", "-v1"]``: the places a label may wrap."""
    return re.findall(r"-v\d+$|[A-Z]*[a-z0-9]+|[A-Z]+(?![a-z])|[^A-Za-z0-9]+[A-Za-z0-9]*", label) or [label]


def _wrap(label: str, font, width_px: float) -> list[str]:
    """``label`` broken into lines no wider than ``width_px`` (at word joints, else inside a word)."""
    lines, line = [], ""
    for word in _words(label):
        while font.getlength(word) > width_px and len(word) > 1:  # a word wider than a tile: cut it
            cut = max(k for k in range(1, len(word) + 1) if font.getlength(word[:k]) <= width_px or k == 1)
            if line:
                lines.append(line)
                line = ""
            lines.append(word[:cut])
            word = word[cut:]
        if line and font.getlength(line + word) > width_px:
            lines.append(line)
            line = word
        else:
            line += word
    return lines + [line] if line else lines


def contact_sheet(tiles: Sequence[tuple[str, np.ndarray]], *, tile_px: int = TILE_PX, columns: int | None = None,
                  font_px: int = LABEL_FONT_PX) -> np.ndarray:
    """One image of all ``tiles`` (label, [H, W, 3] uint8 RGB), in row-major order on a white grid.

    Each image is resized to ``tile_px`` square and labelled underneath (wrapped at CamelCase joints). A cell is
    ``tile_px + 2 * MARGIN_PX`` wide and ``tile_px + label height + 2 * MARGIN_PX`` high, the label height fitting
    the longest wrapped label; ``columns`` defaults to ceil(sqrt(len(tiles))). Returns [rows * cell height,
    columns * cell width, 3] uint8."""
    if not tiles:
        raise ValueError("contact_sheet needs at least one tile")
    if tile_px < 16 or (columns is not None and columns < 1):
        raise ValueError(f"tile_px={tile_px} must be >= 16 and columns={columns} >= 1")
    font = ImageFont.load_default(size=font_px)
    line_px = font_px + 2
    wrapped = [_wrap(label, font, tile_px - 2) for label, _ in tiles]
    label_px = line_px * max(len(lines) for lines in wrapped) + 2
    columns = columns or math.ceil(math.sqrt(len(tiles)))
    rows = math.ceil(len(tiles) / columns)
    cell_w, cell_h = tile_px + 2 * MARGIN_PX, tile_px + label_px + 2 * MARGIN_PX
    sheet = Image.new("RGB", (columns * cell_w, rows * cell_h), "white")
    draw = ImageDraw.Draw(sheet)
    for i, ((_, rgb), lines) in enumerate(zip(tiles, wrapped, strict=True)):
        if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.dtype != np.uint8:
            raise ValueError(f"tile {i} ({tiles[i][0]!r}) is {rgb.dtype} {rgb.shape}; expected uint8 [H, W, 3]")
        x, y = (i % columns) * cell_w + MARGIN_PX, (i // columns) * cell_h + MARGIN_PX
        sheet.paste(Image.fromarray(rgb).resize((tile_px, tile_px), Image.Resampling.LANCZOS), (x, y))
        for k, line in enumerate(lines):
            draw.text((x + 1, y + tile_px + 1 + k * line_px), line, fill="black", font=font)
    return np.asarray(sheet)


def _save_png(rgb: np.ndarray, path: Path) -> Path:
    with atomic_path(path) as tmp:  # never leave a half-written PNG behind
        Image.fromarray(rgb).save(tmp, optimize=True)
    return path


def run_task(version: TaskVersion, out: Path, *, steps: int, seed: int) -> tuple[DemoRow, dict[str, np.ndarray]]:
    """Build ``version`` once: reset with ``seed``, render and save its three views to ``out/<Name>-v<N>_<view>.png``,
    then roll out ``steps`` seeded random ``pd_joint_delta_pos`` actions. Returns the row and the views ([H, W, 3])."""
    import gymnasium as gym

    env = gym.make(version.env_id, control_mode="pd_joint_delta_pos", render_mode="rgb_array")
    try:
        env.reset(seed=seed)
        views = {name: rgb[0] for name, rgb in env.unwrapped.render_views().items()}
        stem = version.env_id.split("/")[-1]
        for name, rgb in views.items():
            _save_png(rgb, out / f"{stem}_{name}.png")
        env.action_space.seed(seed)
        rewards, success, t0 = [], False, time.perf_counter()
        for _ in range(steps):
            _, reward, terminated, truncated, info = env.step(env.action_space.sample())
            rewards.append(float(reward))
            success = success or bool(info["success"])  # one env: a bool or a one-element tensor
            if terminated or truncated:
                env.reset()
        rate = steps / (time.perf_counter() - t0)
    finally:
        env.close()
    row = DemoRow(version.env_id, task_skills(version.spec), steps, rate, bool(np.isfinite(rewards).all()),
                  float(np.mean(rewards)) if rewards else float("nan"), success)
    return row, views


def run_demo(versions: Mapping[str, TaskVersion], out: Path, *, steps: int = 50, seed: int = 0,
             tile_px: int = TILE_PX) -> tuple[list[DemoRow], Path]:
    """:func:`run_task` on the newest version of each task in ``versions``, then the contact sheet of their
    left-overhead views to ``out/contact_sheet.png``. Returns the rows (by task name) and the sheet's path."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rows, tiles = [], []
    for version in tqdm(demo_versions(versions), desc="tasks", unit="task"):
        row, views = run_task(version, out, steps=steps, seed=seed)
        rows.append(row)
        tiles.append((version.env_id.split("/")[-1], views[SHEET_VIEW]))
    sheet = _save_png(contact_sheet(tiles, tile_px=tile_px), out / "contact_sheet.png")
    log.info("wrote %s (%d tasks)", sheet, len(tiles))
    return rows, sheet


def format_table(rows: Sequence[DemoRow]) -> list[str]:
    """One line per row under a header: id, skills, steps/s, rewards finite, mean reward, success."""
    head = ("task", "skills", "steps/s", "finite", "mean r", "success")
    cells = [(r.env_id, ", ".join(r.skills) or "-", f"{r.steps_per_s:.0f}", "yes" if r.rewards_finite else "NO",
              f"{r.mean_reward:.3f}", "yes" if r.success else "no") for r in rows]
    widths = [max(len(c[i]) for c in [head, *cells]) for i in range(len(head))]
    right = {2, 4}  # numbers align right

    def line(c):
        padded = (v.rjust(w) if i in right else v.ljust(w) for i, (v, w) in enumerate(zip(c, widths, strict=True)))
        return "  ".join(padded).rstrip()

    return [line(head), *(line(c) for c in cells)]


__all__ = ["DemoRow", "contact_sheet", "demo_versions", "format_table", "run_demo", "run_task"]
