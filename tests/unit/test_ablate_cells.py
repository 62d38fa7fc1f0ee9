"""run_ablation: saved cells are kept, the missing ones are trained (through gendex.fanout) and every cell comes back
in task x variant order whatever ran where."""

from __future__ import annotations

import json
from dataclasses import asdict
from types import SimpleNamespace

import gendex.train.ablate as ablate
from gendex.train.ablate import Cell, run_ablation


def test_saved_cells_are_kept_and_the_rest_trained_in_order(tmp_path, monkeypatch):
    trained = []

    def fake_run_cell(version, variant, budget, out, **kwargs):
        trained.append((version.name, variant))
        return Cell(version.name, variant, budget, kwargs["eval_episodes"], successes=len(trained))

    monkeypatch.setattr(ablate, "run_cell", fake_run_cell)
    versions = [SimpleNamespace(name="TaskA"), SimpleNamespace(name="TaskB")]
    saved = tmp_path / "TaskA" / "full" / "cell.json"
    saved.parent.mkdir(parents=True)
    saved.write_text(json.dumps(asdict(Cell("TaskA", "full", 10, 3, successes=3))))
    stale = tmp_path / "TaskB" / "full" / "cell.json"  # another budget: trained again
    stale.parent.mkdir(parents=True)
    stale.write_text(json.dumps(asdict(Cell("TaskB", "full", 99, 3, successes=1))))
    seen = []
    cells = run_ablation(versions, 10, tmp_path, variants=("full", "rl_only"), eval_episodes=3,
                         progress=lambda c: seen.append((c.task, c.variant)))
    assert [(c.task, c.variant) for c in cells] == [("TaskA", "full"), ("TaskA", "rl_only"), ("TaskB", "full"),
                                                     ("TaskB", "rl_only")]
    assert trained == [("TaskA", "rl_only"), ("TaskB", "full"), ("TaskB", "rl_only")]
    assert cells[0].successes == 3 and cells[2].budget == 10
    assert sorted(seen) == sorted((c.task, c.variant) for c in cells)
