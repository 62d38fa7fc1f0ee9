"""Suites, eval_info.json and leaderboard result files: what is checked, what is written (no simulator)."""

from __future__ import annotations

import json

import pytest
from board_data import SUITE, entry, synthetic_info, write

from gendex.eval.leaderboard import LeaderboardError, build_site, load_entries, markdown
from gendex.eval.metrics import wilson
from gendex.eval.suite import SuiteError, load_suite


def test_suites_load_with_their_hash_and_seeds_far_from_the_datasets():
    from gendex.data.datasets import DATASETS_DIR, load_manifest

    top = max(t.seed + (t.max_attempts or 20 * t.episodes) for p in DATASETS_DIR.glob("*.yaml")
              for t in load_manifest(p.stem).tasks)
    for name in ("gendex-ref-v1", "gendex-skills-v1", "gendex-lib-v1"):
        s = load_suite(name)
        assert len(s.hash) == 64 and s.episodes == 50 and s.metric == "success_at_end"
        assert s.seed > top and s.seed + s.episodes < 50_000_000  # datasets below, the gate's seeds above
    assert len(load_suite("gendex-skills-v1").tasks) == 13


def test_a_bad_suite_is_refused(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("name: bad\ndescription: x\ntasks: [PutAppleBowl]\nseed: 5\nmetric: success_sometimes\n")
    with pytest.raises(SuiteError) as e:
        load_suite(path)
    assert "metric 'success_sometimes'" in str(e.value) and "seed 5 is below" in str(e.value)
    assert "versioned GenDex ids" in str(e.value)


def test_eval_info_has_lerobots_fields_and_wilson_intervals_per_task():
    info = synthetic_info({"GenDex/PutAppleBowl-v1": 7, "GenDex/PickUpBottle-v2": 10, "GenDex/OpenCabinet-v1": 0})
    ep = info["per_episode"][0]
    assert {"episode_ix", "sum_reward", "max_reward", "success", "seed"} <= set(ep)
    assert {"avg_sum_reward", "avg_max_reward", "pc_success", "eval_s", "eval_ep_s"} <= set(info["aggregated"])
    t = info["per_task"]["GenDex/PutAppleBowl-v1"]
    assert t["successes"] == 7 and t["pc_success"] == 70.0
    assert t["wilson95"] == pytest.approx([100 * x for x in wilson(7, 10)])
    assert info["aggregated"]["pc_success"] == pytest.approx(100 * 17 / 30)
    assert info["suite"]["complete"] is False  # 10 of the suite's 50 episodes per task
    assert [e["seed"] for e in info["per_episode"][:3]] == [2_000_000, 2_000_001, 2_000_002]


def test_result_files_are_validated(tmp_path):
    info = synthetic_info({"GenDex/PutAppleBowl-v1": 3, "GenDex/PickUpBottle-v2": 5, "GenDex/OpenCabinet-v1": 1})
    write(tmp_path, "ok", entry("Random", info))
    assert [e.method for e in load_entries(SUITE, tmp_path)] == ["Random"]
    write(tmp_path, "bad", entry("X", info, policy_kind="magic"))
    with pytest.raises(LeaderboardError, match="policy_kind 'magic' is not one of"):
        load_entries(SUITE, tmp_path)
    write(tmp_path, "bad", entry("X", info, colour="red"))
    with pytest.raises(LeaderboardError, match="colour"):
        load_entries(SUITE, tmp_path)
    broken = json.loads(json.dumps(info))
    broken["per_task"]["GenDex/PutAppleBowl-v1"]["successes"] = 9
    write(tmp_path, "bad", entry("X", broken))
    with pytest.raises(LeaderboardError, match="9 of 10 is not 30.0 %"):
        load_entries(SUITE, tmp_path)
    other = synthetic_info({t: 1 for t in load_suite("gendex-skills-v1").tasks}, suite_name="gendex-skills-v1")
    write(tmp_path, "bad", entry("X", other))
    with pytest.raises(LeaderboardError, match="result on suite 'gendex-skills-v1', filed under 'gendex-ref-v1'"):
        load_entries(SUITE, tmp_path)


def test_a_result_on_another_version_of_the_suite_is_marked_stale(tmp_path):
    info = synthetic_info({"GenDex/PutAppleBowl-v1": 3, "GenDex/PickUpBottle-v2": 5, "GenDex/OpenCabinet-v1": 1})
    info["suite"]["hash"] = "0" * 64
    write(tmp_path, "old", entry("Old", info))
    [e] = load_entries(SUITE, tmp_path)
    assert e.stale and "Old (stale)" in markdown(tmp_path)


def test_site_and_markdown_hold_every_result_best_first(tmp_path):
    root = tmp_path / "board"
    for name, k in (("weak", 2), ("strong", 9), ("middle", 5)):
        write(root, name, entry(name.title(), synthetic_info({t: k for t in load_suite(SUITE).tasks})))
    pages = build_site(tmp_path / "site", root)
    assert [p.name for p in pages] == ["index.html", f"{SUITE}.html"]
    page = (tmp_path / "site" / f"{SUITE}.html").read_text()
    assert page.index("Strong") < page.index("Middle") < page.index("Weak")
    assert (tmp_path / "site" / "results" / SUITE / "strong.json").is_file()
    md = markdown(root)
    assert "| Strong | baseline | 90.0 [" in md and "`GenDex/OpenCabinet-v1`" in md


def test_the_committed_board_is_valid_current_and_written_into_the_docs():
    """Every result under leaderboard/ validates against its suite's current file (none stale), carries a per-episode
    seed for each of the suite's seeds it ran, and docs/leaderboard.md is what ``gendex leaderboard build`` writes."""
    from gendex.eval.leaderboard import LEADERBOARD_DIR, REPO_ROOT, suites_with_results

    suites = suites_with_results()
    assert "gendex-ref-v1" in suites
    for name in suites:
        suite = load_suite(name)
        entries = load_entries(name)
        assert entries and not [e.file for e in entries if e.stale]
        for e in entries:
            rows = e.eval_info["per_episode"]
            for task in e.per_task:
                seeds = [r["seed"] for r in rows if r["task"] == task]
                assert seeds == list(range(suite.seed, suite.seed + len(seeds))), (e.file, task)
    assert (REPO_ROOT / "docs" / "leaderboard.md").read_text() == markdown(LEADERBOARD_DIR)
