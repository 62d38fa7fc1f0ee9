"""`gendex demo`'s task pass on a real task: only the newest version runs, its views and the contact sheet are written,
and the table has one line for it."""

import numpy as np
from PIL import Image
from typer.testing import CliRunner

import gendex_envs.registry
from gendex.cli import app
from gendex.demo import MARGIN_PX, TILE_PX
from gendex_envs.task_env import VIEW_CAMERAS


def test_demo_renders_and_rolls_out_only_the_newest_version(tmp_path, monkeypatch, task_version):
    newest = task_version("LiftApple")
    older = task_version("LiftApple", newest.version - 1)
    monkeypatch.setattr(gendex_envs.registry, "registered_tasks",
                        lambda: {v.env_id: v for v in (older, newest)})
    result = CliRunner().invoke(app, ["demo", "--out", str(tmp_path), "--steps", "3", "--generate", "0",
                                      "--collect", "0"])
    assert result.exit_code == 0, result.output
    stem = newest.env_id.split("/")[-1]
    assert sorted(p.name for p in tmp_path.glob("*.png")) == sorted(
        [f"{stem}_{c}.png" for c in VIEW_CAMERAS] + ["contact_sheet.png"])
    lines = result.output.splitlines()
    head = next(i for i, line in enumerate(lines) if line.split()[:2] == ["task", "skills"])
    cells = lines[head + 1].split()
    assert cells[0] == newest.env_id and cells[1] == "lift" and cells[3] == "yes"  # finite rewards
    assert older.env_id not in result.output
    sheet = np.asarray(Image.open(tmp_path / "contact_sheet.png"))
    assert sheet.shape[1] == TILE_PX + 2 * MARGIN_PX
    tile = sheet[MARGIN_PX:MARGIN_PX + TILE_PX, MARGIN_PX:MARGIN_PX + TILE_PX]
    assert tile.std() > 10  # a rendered scene, not a blank tile
