"""Made-up evaluation results for the leaderboard tests (tests/unit/test_leaderboard.py, tests/web/)."""

from __future__ import annotations

import json
from pathlib import Path

from gendex.eval.suite import load_suite, suite_task_digests
from gendex.eval.suite_run import eval_info

SUITE = "gendex-ref-v1"


def synthetic_info(rates: dict[str, int], episodes: int = 10, suite_name: str = SUITE,
                   groups: dict[str, str] | None = None) -> dict:
    """eval_info of a made-up run: ``rates[task]`` successes of ``episodes`` on every task of the suite (as
    committed: with their digests); ``groups``: each task's group (its skills)."""
    suite = load_suite(suite_name)
    seeds = suite.seeds(episodes)
    rows = [{"task": t, "seed": s, "sum_reward": 1.0, "max_reward": 0.5, "success_at_end": k < rates[t],
             "success_once": k < rates[t] + 1, "length": 100 + k, "failure": None}
            for t in suite.tasks for k, s in enumerate(seeds)]
    return eval_info(suite, "random", rows, seeds, 12.0, task_digests=suite_task_digests(suite), groups=groups)


def entry(method: str, info: dict, **changes) -> dict:
    return {"method": method, "authors": "GenDex", "code": "https://example.org/gendex", "policy_kind": "baseline",
            "training_data": "none", "date": "2026-11-25", "policy": info["policy"], "sees_simulator_state": False,
            "eval_info": info, **changes}


def write(root: Path, name: str, data: dict, suite: str = SUITE) -> Path:
    (root / suite).mkdir(parents=True, exist_ok=True)
    path = root / suite / f"{name}.json"
    path.write_text(json.dumps(data))
    return path
