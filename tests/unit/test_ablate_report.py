"""The ablation's bookkeeping: env steps to N successes, and the Markdown table + plot it writes."""

import math

import pytest

from gendex.train.ablate import Cell, StageRecord, _split, ablation_markers, load_cell, write_results
from gendex.train.presets import TrainingError


def _cell(variant, successes, train=10_000, collect=500, eval_steps=1600):
    return Cell(task="PickUpBottle", variant=variant, budget=20_000, eval_episodes=20, successes=successes,
                train_steps=train, collect_steps=collect, eval_steps=eval_steps,
                stages=[StageRecord("approach_bottle", "motion_planning", "arm"),
                        StageRecord("grasp_bottle", "RL", "hand", train, collect, 0.5)])


def test_steps_to_n_counts_training_collection_and_episodes():
    c = _cell("mp_rl", successes=10)  # 50 %, 80 steps per evaluation episode
    assert c.steps_to(1000) == pytest.approx(10_000 + 500 + 1000 / 0.5 * 80)
    assert math.isinf(_cell("subgoals", successes=0).steps_to(1000))


def test_budget_split_needs_a_rollout_per_stage():
    assert _split(50_000, 2, 1024) == 25_000
    with pytest.raises(TrainingError, match="less than one PPO rollout"):
        _split(3000, 4, 1024)


def test_results_table_is_written_and_replaced_in_place(tmp_path):
    md = tmp_path / "results.md"
    md.write_text("# Results\n\nintro kept\n")
    cells = [_cell("mp_rl", 10), _cell("subgoals", 0)]
    write_results(cells, md, tmp_path / "plot.png", "gendex ablate --budget 20000", 20_000)
    text = md.read_text()
    begin, end = ablation_markers(20_000)
    assert "intro kept" in text and text.count(begin) == 1 and text.count(end) == 1
    assert "| PickUpBottle | (iv) motion planning + RL | 10/20 (50 %) | 0.17 M |" in text
    assert "| PickUpBottle | (ii) sub-goals | 0/20 (0 %) | — (no success) |" in text
    assert "60 %, 88.6 M" in text and "grasp_bottle: 50 %" in text and "approach_bottle: planner" in text
    assert (tmp_path / "plot.png").stat().st_size > 1000
    write_results(cells[:1], md, tmp_path / "plot.png", "gendex ablate --budget 20000", 20_000)  # rewrite in place
    assert md.read_text().count(begin) == 1 and "(ii) sub-goals" not in md.read_text()
    write_results(cells[:1], md, tmp_path / "plot2.png", "gendex ablate --budget 99000", 99_000)  # another block
    assert md.read_text().count(begin) == 1 and md.read_text().count(ablation_markers(99_000)[0]) == 1


def test_cell_round_trip(tmp_path):
    import json
    c = _cell("mp_rl", 7)
    (tmp_path / "cell.json").write_text(json.dumps(c.as_dict()))
    back = load_cell(tmp_path / "cell.json")
    assert back == c
