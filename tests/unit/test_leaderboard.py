"""Suites, eval_info.json and leaderboard result files: what is checked, what is written (no simulator)."""

from __future__ import annotations

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


REF_GROUPS = {"GenDex/PutAppleBowl-v1": "put_in", "GenDex/PickUpBottle-v2": "lift",
              "GenDex/OpenCabinet-v1": "open_door"}


def test_eval_info_is_in_lerobot_04s_layout_with_wilson_intervals_per_task_and_group():
    info = synthetic_info({"GenDex/PutAppleBowl-v1": 7, "GenDex/PickUpBottle-v2": 10, "GenDex/OpenCabinet-v1": 0},
                          groups={**REF_GROUPS, "GenDex/OpenCabinet-v1": "lift"})
    assert info["layout"] == "lerobot-0.4" and "per_episode" not in info and "aggregated" not in info
    first = info["per_task"][0]
    assert {"task_group", "task_id", "metrics"} <= set(first)
    assert {"sum_rewards", "max_rewards", "successes", "video_paths"} <= set(first["metrics"])  # lerobot's keys
    assert first["task_id"] == "GenDex/PutAppleBowl-v1" and first["task_group"] == "put_in"
    assert first["metrics"]["successes"] == [True] * 7 + [False] * 3 and first["n_successes"] == 7
    assert first["metrics"]["seeds"][:3] == [2_000_000, 2_000_001, 2_000_002]
    assert first["wilson95"] == pytest.approx([100 * x for x in wilson(7, 10)])
    assert {"avg_sum_reward", "avg_max_reward", "pc_success", "n_episodes", "eval_s", "eval_ep_s",
            "video_paths"} <= set(info["overall"])
    assert info["overall"]["pc_success"] == pytest.approx(100 * 17 / 30) and info["overall"]["n_episodes"] == 30
    assert info["per_group"]["lift"]["pc_success"] == pytest.approx(50.0)  # bottle 10/10 + cabinet 0/10
    assert info["per_group"]["lift"]["tasks"] == ["GenDex/PickUpBottle-v2", "GenDex/OpenCabinet-v1"]
    assert info["per_group"]["put_in"]["wilson95"] == pytest.approx([100 * x for x in wilson(7, 10)])
    assert info["suite"]["complete"] is False  # 10 of the suite's 50 episodes per task


def _new_layout_forgeries():
    def count(d):
        d["per_task"][0]["n_successes"] = 9

    def rate(d):
        d["per_task"][0]["pc_success"] = 90.0

    def flip(d):  # a failed episode turned into a success, the counts left as they were
        d["per_task"][0]["metrics"]["successes"][-1] = True

    def overall(d):
        d["overall"]["pc_success"] = 100.0

    def group(d):
        d["per_group"]["put_in"]["pc_success"] = 100.0

    def drop(d):  # the hardest task left out, every sum made to agree
        d["per_task"] = [t for t in d["per_task"] if t["task_id"] != "GenDex/OpenCabinet-v1"]
        del d["per_group"]["open_door"]
        d["overall"].update(pc_success=85.0, n_episodes=20)

    def short(d):
        d["per_task"][1]["metrics"]["seeds"].pop()

    return [("n_successes 9 is not the 7", count), ("7 of 10 is not 90.0 %", rate),
            ("n_successes 7 is not the 8", flip), ("overall pc_success 100.0", overall),
            ("group 'put_in'", group), ("have no result", drop), ("per-episode lists hold", short)]


@pytest.mark.parametrize("match, forge", _new_layout_forgeries(), ids=lambda x: x if isinstance(x, str) else "")
def test_a_new_layout_result_whose_numbers_do_not_add_up_is_refused_by_name(tmp_path, match, forge):
    info = synthetic_info({"GenDex/PutAppleBowl-v1": 7, "GenDex/PickUpBottle-v2": 10, "GenDex/OpenCabinet-v1": 0},
                          groups=REF_GROUPS)
    write(tmp_path, "ok", entry("Honest", info))
    assert [e.aggregated["pc_success"] for e in load_entries(SUITE, tmp_path)] == [pytest.approx(100 * 17 / 30)]
    forge(info)
    write(tmp_path, "ok", entry("Forged", info))
    with pytest.raises(LeaderboardError, match=match):
        load_entries(SUITE, tmp_path)


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
    unflagged = entry("X", info)
    del unflagged["sees_simulator_state"]
    write(tmp_path, "bad", unflagged)
    with pytest.raises(LeaderboardError, match="sees_simulator_state"):
        load_entries(SUITE, tmp_path)
    other = synthetic_info({t: 1 for t in load_suite("gendex-skills-v1").tasks}, suite_name="gendex-skills-v1")
    write(tmp_path, "bad", entry("X", other))
    with pytest.raises(LeaderboardError, match="result on suite 'gendex-skills-v1', filed under 'gendex-ref-v1'"):
        load_entries(SUITE, tmp_path)


def test_per_skill_columns_pool_the_tasks_of_each_skill(tmp_path):
    groups = {"GenDex/PutAppleBowl-v1": "put_in", "GenDex/PickUpBottle-v2": "lift",
              "GenDex/OpenCabinet-v1": "open_door+lift"}
    info = synthetic_info({"GenDex/PutAppleBowl-v1": 7, "GenDex/PickUpBottle-v2": 10, "GenDex/OpenCabinet-v1": 2},
                          groups=groups)
    write(tmp_path / "board", "ok", entry("Skilled", info, sees_simulator_state=True))
    [e] = load_entries(SUITE, tmp_path / "board")
    assert e.skills == {"put_in": (7, 10), "lift": (12, 20), "open_door": (2, 10)}
    build_site(tmp_path / "site", tmp_path / "board")
    page = (tmp_path / "site" / f"{SUITE}.html").read_text()
    assert 'data-key="skill-lift"' in page and 'data-value="60.0000"' in page and ">yes<" in page
    md = markdown(tmp_path / "board")
    assert "| method | put in | lift | open door |" in md and "| Skilled | 70 | 60 | 20 |" in md


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
    assert "| Strong | baseline | no | 90.0 [" in md and "`GenDex/OpenCabinet-v1`" in md


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
            for task, t in e.per_task.items():
                assert t["seeds"] == list(range(suite.seed, suite.seed + t["episodes"])), (e.file, task)
    assert (REPO_ROOT / "docs" / "leaderboard.md").read_text() == markdown(LEADERBOARD_DIR)


@pytest.mark.parametrize("name", ["gendex-ref-v2", "gendex-skills-v2", "gendex-lib-v2"])
def test_holding_still_and_random_actions_solve_no_task_of_a_v2_suite_past_5_percent(name):
    """The v2 suites are calibrated: their filed hold and random results cover every task with the suite's 50
    episodes, and solve none in more than 5 % of them at any step (``successes_once``, stricter than the metric)."""
    suite = load_suite(name)
    entries = {e.policy: e for e in load_entries(name)}
    for policy in ("hold", "random"):
        info = entries[policy].eval_info
        assert info["layout"] == "lerobot-0.4" and info["suite"]["complete"], (name, policy)
        rows = {row["task_id"]: row["metrics"] for row in info["per_task"]}
        assert sorted(rows) == sorted(suite.tasks), (name, policy)
        for task, metrics in rows.items():
            assert len(metrics["successes_once"]) == suite.episodes == 50, (name, policy, task)
            assert sum(metrics["successes_once"]) <= 0.05 * 50, (name, policy, task, sum(metrics["successes_once"]))
