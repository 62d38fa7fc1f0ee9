"""The ``wiped`` condition's data: where a spill's marks lie (a grid inside its edge), what the spec refuses, and how
the wipe primitive lays its passes over the marks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gendex.solve.wipe import WIPE_EDGE_M, WIPE_OVERRUN_M, passes
from gendex_envs.assets.catalog import get_asset
from gendex_envs.errors import TaskSpecError
from gendex_envs.spec import parse_task_spec
from gendex_envs.wiping import spill_marks

SPILLS = ("spill_round", "spill_square", "spill_long")


@pytest.mark.parametrize("asset", SPILLS)
def test_marks_lie_on_a_centred_grid_inside_the_stain(asset):
    p = get_asset(asset).entry.params
    marks = np.array(spill_marks(p))
    assert len(marks) >= 10
    assert np.allclose(marks.mean(axis=0), 0.0, atol=1e-6)  # centred on the stain
    inset = float(p["marks_inset_m"])
    if p["shape"] == "round":
        assert (np.linalg.norm(marks, axis=1) <= p["size_x_m"] / 2 - inset + 1e-9).all()
    else:
        assert (np.abs(marks) <= np.array([p["size_x_m"], p["size_y_m"]]) / 2 - inset + 1e-9).all()
    gaps = np.linalg.norm(marks[:, None] - marks[None], axis=-1) + np.eye(len(marks))
    assert gaps.min() == pytest.approx(p["marks_pitch_m"])


def test_an_asset_without_a_pitch_has_no_marks():
    assert spill_marks(get_asset("sponge_block").entry.params) == []


def test_passes_cover_every_mark_with_the_footprint_less_its_edges():
    marks = np.array(spill_marks(get_asset("spill_square").entry.params))
    along = np.array([math.cos(0.3), math.sin(0.3)])
    width = 0.07
    plan = passes(marks, along, width)
    across = np.array([-along[1], along[0]])
    for m in marks:
        covered = [abs((m - a) @ across) <= width / 2 - WIPE_EDGE_M + 1e-3
                   and min(a @ along, b @ along) + WIPE_OVERRUN_M - 1e-6 <= m @ along
                   <= max(a @ along, b @ along) - WIPE_OVERRUN_M + 1e-6 for a, b in plan]
        assert any(covered), m
    assert all((b - a) @ along * (1 if k % 2 == 0 else -1) > 0 for k, (a, b) in enumerate(plan))  # back and forth


def _spec(cond: dict) -> dict:
    return {"name": "T", "instruction": "Wipe it.",
            "objects": [{"name": "sponge", "asset": "sponge_block", "pos_m": [0.1, -0.2, 0.0]},
                        {"name": "spill", "asset": "spill_round", "pos_m": [0.1, 0.0, 0.0], "fixed": True}],
            "stages": [{"name": "s", "instruction": "Wipe it.", "skill": "wipe", "method": "motion_planning",
                        "control_joint": "arm", "target": "spill"}],
            "success": {"description": "Done.", "conditions": [cond]}}


@pytest.mark.parametrize("cond, words", [
    ({"type": "wiped", "object": "sponge", "min_fraction": 0.9}, "target is required"),
    ({"type": "wiped", "object": "sponge", "target": "spill"}, "min_fraction is required"),
    ({"type": "wiped", "object": "sponge", "target": "spill", "min_fraction": 1.5}, r"\(0, 1\]"),
    ({"type": "wiped", "object": "sponge", "target": "spill", "min_fraction": 0.9, "min_press_n": 0}, "> 0"),
    ({"type": "wiped", "object": "sponge", "target": "spill", "min_fraction": 0.9, "max_xy_m": 0.1},
     "does not apply to type 'wiped'"),
    ({"type": "wiped", "object": "sponge", "target": "sponge", "min_fraction": 0.9}, "another object"),
])
def test_the_spec_refuses_bad_wipes_naming_the_field(cond, words):
    with pytest.raises(TaskSpecError, match=words):
        parse_task_spec(_spec(cond), source="test")


def test_a_good_wipe_parses():
    spec = parse_task_spec(_spec({"type": "wiped", "object": "sponge", "target": "spill", "min_fraction": 0.9}))
    assert spec.success.conditions[0].min_press_n is None  # the default, 1 N, applies
