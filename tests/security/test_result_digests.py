"""Results record the digest of each task's files, and the board refuses those whose digests differ from the suite's
(issue 43, identity): a score made on a copy with another reward or spec under a suite's task id is not a score on
the suite. ``gendex eval`` refuses to run such a task unless asked.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from gendex_envs.registry import REPO_TASKS_DIR, register_tasks
from gendex_envs.task_version import TaskLayout, TaskVersion


# ------------------------------------------------------------------------------- results record task digests
def _shadow(root: Path, env_id: str = "GenDex/PutAppleBowl-v1") -> TaskVersion:
    """A copy of a committed version under the same id with another reward and spec."""
    name, version = env_id.split("/")[1].rsplit("-v", 1)
    folder = root / name / f"v{version}"
    TaskVersion.at(REPO_TASKS_DIR / name / f"v{version}").copy_to(folder)
    reward = TaskLayout(folder).reward
    reward.write_text(reward.read_text() + "\n\ndef compute_dense_reward(env, obs, action, info):\n    return 0.0 * "
                      "action.sum(dim=-1) + 1.0\n")
    spec = TaskLayout(folder).spec
    spec.write_text(spec.read_text().replace("max_episode_steps: 200", "max_episode_steps: 150"))
    return TaskVersion.at(folder)


def _result(root: Path, info: dict) -> Path:
    from board_data import entry, write

    return write(root, "copy", entry("Random on a copy", info))


def test_a_result_on_a_changed_copy_under_the_suite_id_is_refused_by_the_board(tmp_path):
    from board_data import SUITE, synthetic_info

    from gendex.eval.leaderboard import ResultDigestError, load_entries
    from gendex.eval.suite import load_suite, suite_task_digests

    copy = _shadow(tmp_path / "tasks")
    want = suite_task_digests(load_suite(SUITE))["GenDex/PutAppleBowl-v1"]
    assert copy.file_digest() != want
    info = synthetic_info({t: 10 for t in load_suite(SUITE).tasks})
    board = tmp_path / "board"
    _result(board, info)
    assert [e.method for e in load_entries(SUITE, board)] == ["Random on a copy"]  # the genuine files: accepted

    info["task_digests"]["GenDex/PutAppleBowl-v1"] = copy.file_digest()
    _result(board, info)
    with pytest.raises(ResultDigestError) as err:
        load_entries(SUITE, board)
    assert "GenDex/PutAppleBowl-v1" in str(err.value) and copy.file_digest() in str(err.value)
    assert want in str(err.value) and "GenDex/PickUpBottle-v2" not in str(err.value)

    del info["task_digests"]  # a result that does not say what it ran on
    _result(board, info)
    with pytest.raises(ResultDigestError, match="no 'task_digests'"):
        load_entries(SUITE, board)


def test_eval_refuses_a_shadowed_suite_task_and_the_board_refuses_its_result(tmp_path):
    from board_data import SUITE

    from gendex.eval.leaderboard import ResultDigestError, load_entries
    from gendex.eval.suite import TaskDigestError, load_suite, ran_task_digests
    from gendex.eval.suite_run import eval_info, run_suite

    suite = load_suite(SUITE)
    copy = _shadow(tmp_path / "tasks")
    assert register_tasks([copy.tasks_root], override=True) == ["GenDex/PutAppleBowl-v1"]
    try:
        def never(spec):
            raise AssertionError("no policy may be built: the run is refused first")

        out = tmp_path / "eval"
        with pytest.raises(TaskDigestError) as err:
            run_suite(suite, "random", never, out)
        assert "GenDex/PutAppleBowl-v1" in str(err.value) and copy.file_digest() in str(err.value)
        assert not out.exists()  # refused before anything was written

        ran = ran_task_digests(suite.tasks)  # what a run with --allow-changed-tasks records
        assert ran["GenDex/PutAppleBowl-v1"] == copy.file_digest()
        seeds = suite.seeds(2)
        rows = [{"task": t, "seed": s, "sum_reward": 1.0, "max_reward": 1.0, "success_at_end": True,
                 "success_once": True, "length": 10, "failure": None} for t in suite.tasks for s in seeds]
        _result(tmp_path / "board", eval_info(suite, "random", rows, seeds, 1.0, task_digests=ran))
        with pytest.raises(ResultDigestError, match="GenDex/PutAppleBowl-v1 ran on files with digest"):
            load_entries(SUITE, tmp_path / "board")
    finally:
        assert register_tasks([REPO_TASKS_DIR], override=True) == ["GenDex/PutAppleBowl-v1"]


def test_the_committed_results_record_the_committed_digests():
    from gendex.eval.leaderboard import LEADERBOARD_DIR
    from gendex.eval.suite import load_suite, suite_task_digests

    files = sorted(LEADERBOARD_DIR.glob("*/*.json"))
    assert files
    for path in files:
        recorded = json.loads(path.read_text())["eval_info"]["task_digests"]
        assert recorded == suite_task_digests(load_suite(path.parent.name)), path


def test_file_digest_covers_every_file_and_never_follows_links(tmp_path):
    copy = _shadow(tmp_path / "tasks")
    first = copy.file_digest()
    assert copy.file_digest() == first  # stable
    for rel in ("stage_rewards/grasp_apple.py", "policies/grasp_apple.zip", "start_states/grasp_apple.npz",
                "stage_rewards/notes.pyc", ".hidden"):
        path = copy.root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        before = copy.file_digest()
        path.write_bytes(path.read_bytes() + b"x" if path.exists() else b"x")
        assert copy.file_digest() != before, rel
    # bytecode caches are never read (modules run from their checked text) and pip writes them when it installs
    # the library: an installed copy digests as the checkout does
    before = copy.file_digest()
    for rel in ("__pycache__/reward.cpython-311.pyc", "stage_rewards/__pycache__/grasp_apple.cpython-311.pyc"):
        (copy.root / rel).parent.mkdir(parents=True, exist_ok=True)
        (copy.root / rel).write_bytes(b"x")
    assert copy.file_digest() == before
    (copy.root / "solvability.json").write_text("{}")  # a measurement, not part of the version
    before = copy.file_digest()
    (copy.root / "solvability.json").write_text('{"renewed": true}')
    assert copy.file_digest() == before
    (copy.root / "zero").symlink_to("/dev/zero")  # read, it would never end
    os.mkfifo(copy.root / "pipe")  # opened, it would block
    linked = copy.file_digest()
    assert linked != before
    (copy.root / "zero").unlink()
    (copy.root / "zero").symlink_to("/dev/null")
    assert copy.file_digest() != linked


def test_gendex_eval_refuses_a_suite_task_a_tasks_path_folder_replaced(tmp_path):
    """End to end: a user who lets a downloaded folder take PutAppleBowl-v1's id (GENDEX_ALLOW_OVERRIDE=1) cannot
    evaluate on the reference suite with it unless --allow-changed-tasks; nothing is written."""
    import subprocess
    import sys

    copy = _shadow(tmp_path / "tasks")
    repo = Path(__file__).resolve().parents[2]
    env = {**os.environ, "GENDEX_TASKS_PATH": str(copy.tasks_root), "GENDEX_ALLOW_OVERRIDE": "1",
           "PYTHONPATH": str(repo)}
    out = tmp_path / "eval"
    done = subprocess.run([sys.executable, "-m", "gendex.cli", "eval", "--suite", "gendex-ref-v1", "--policy", "hold",
                           "--episodes", "1", "--out", str(out)], cwd=repo, env=env, capture_output=True, text=True,
                          timeout=240)
    assert done.returncode == 2, done.stderr[-2000:]
    assert "GenDex/PutAppleBowl-v1" in done.stderr and copy.file_digest() in done.stderr
    assert not out.exists()
