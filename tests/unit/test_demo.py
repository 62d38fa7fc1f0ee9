"""The demo's task pass (gendex.demo): which versions it runs, the contact sheet it lays out, the table it prints."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gendex.demo import MARGIN_PX, DemoRow, contact_sheet, demo_versions, format_table
from gendex_envs.registry import registered_tasks
from gendex_envs.task_version import TaskVersion


def _version(name: str, version: int) -> TaskVersion:
    return TaskVersion(root=Path("/nowhere") / name / f"v{version}", name=name, version=version)


def test_demo_runs_the_highest_version_of_each_task_by_number_not_text():
    versions = {v.env_id: v for v in (_version("Lift", 2), _version("Lift", 10), _version("Lift", 9),
                                      _version("Close", 0), _version("Open", 1), _version("Open", 0))}
    assert [v.env_id for v in demo_versions(versions)] == ["GenDex/Close-v0", "GenDex/Lift-v10", "GenDex/Open-v1"]


def test_demo_on_the_library_runs_one_version_per_task_the_newest():
    library = registered_tasks()
    chosen = demo_versions(library)
    names = {v.name for v in library.values()}
    assert len(chosen) == len(names) < len(library)  # the library has older versions; the demo skips them
    for v in chosen:
        assert v.version == max(w.version for w in library.values() if w.name == v.name)


COLOURS = [(255, 0, 0), (0, 160, 0), (0, 0, 255), (200, 200, 0), (120, 0, 120)]


def _solid(colour, px: int) -> np.ndarray:
    return np.broadcast_to(np.array(colour, dtype=np.uint8), (px, px, 3)).copy()


def test_contact_sheet_lays_tiles_out_row_major_with_labels_under_them():
    tiles = [(f"Task{i}-v0", _solid(c, 40 + 8 * i)) for i, c in enumerate(COLOURS)]  # sizes differ: all resized
    sheet = contact_sheet(tiles, tile_px=32, columns=3)
    cell_w = 32 + 2 * MARGIN_PX
    assert sheet.dtype == np.uint8 and sheet.shape[1] == 3 * cell_w and sheet.shape[0] % 2 == 0  # 5 tiles: 2 rows
    cell_h = sheet.shape[0] // 2
    assert cell_h > cell_w  # room for the label
    for i, colour in enumerate(COLOURS):
        top, left = (i // 3) * cell_h + MARGIN_PX, (i % 3) * cell_w + MARGIN_PX
        tile = sheet[top:top + 32, left:left + 32].astype(int)
        assert np.abs(tile - colour).max() <= 1, f"tile {i} is not its image"
        label = sheet[top + 32:(i // 3 + 1) * cell_h, left:left + 32]
        assert (label.min(axis=-1) < 128).any(), f"tile {i} has no label text"
    empty = sheet[cell_h:, 2 * cell_w:]  # the sixth cell has no tile
    assert (empty == 255).all()


def test_contact_sheet_wraps_a_long_label_onto_more_lines_and_defaults_to_a_square_grid():
    short = contact_sheet([("A-v0", _solid(COLOURS[0], 8))] * 4, tile_px=48)
    long = contact_sheet([("CloseCabinetLeftHingeThenSetBlockLargeOnCuttingBoard-v1", _solid(COLOURS[0], 8))]
                         + [("A-v0", _solid(COLOURS[0], 8))] * 3, tile_px=48)
    assert short.shape[1] == long.shape[1] == 2 * (48 + 2 * MARGIN_PX)  # 4 tiles: 2 x 2
    assert long.shape[0] > short.shape[0]
    with pytest.raises(ValueError, match="uint8"):
        contact_sheet([("bad", np.zeros((8, 8, 3), dtype=np.float32))])


def test_the_table_has_a_header_and_one_line_per_task():
    rows = [DemoRow("GenDex/LiftApple-v2", ("lift",), 50, 41.7, True, 0.0123, False),
            DemoRow("GenDex/OpenDrawer-v1", (), 50, 9.2, False, float("nan"), True)]
    lines = format_table(rows)
    assert len(lines) == 3 and lines[0].split()[:2] == ["task", "skills"]
    assert lines[1].split() == ["GenDex/LiftApple-v2", "lift", "42", "yes", "0.012", "no"]
    assert lines[2].split() == ["GenDex/OpenDrawer-v1", "-", "9", "NO", "nan", "yes"]
