"""``gendex generate`` with tasks in parallel commits what one process commits (issue: scale out on Ray).

A parallel batch generates each task from a guess of what the tasks before it committed, and publishes a result
only when its guess held (``generator.pipeline._generate_in_parallel``). The default suite runs the batch logic in
this process with a scripted gate whose first verdict drops a proposal, so one guess fails and a task is generated
again; the slow test runs real worker processes with the real gate.
"""

import functools
import logging
from collections import deque
from pathlib import Path

import pytest

from gendex.fanout import Backend
from generator.backends.registry import make_backend
from generator.pipeline import BatchState, generate
from generator.steps.gate import GateResult


def _tree(root: Path) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(root.rglob("*"))
            if p.is_file() and ".drafts" not in p.parts}


def _scripted_gate(dropped: set[str], seen: list[str]):
    """A gate that fails the proposals named in ``dropped`` (or, while that is empty, the first one it sees, which it
    adds) and passes every other; ``seen`` collects the names in call order."""
    def gate(draft, name, attempts, workers=1):
        seen.append(name)
        if not dropped:
            dropped.add(name)
        if name in dropped:
            return GateResult(3, 0, 0, [1, 2, 3], {"grasp_x/grasp/slipped": 3}, planned_attempts=10)
        return GateResult(10, 10, 900, list(range(10)), {})
    return gate


def _two_ahead(make_worker, jobs, backend=None, *, ahead=None):
    """The fan-out's ordering with two jobs submitted before a result is taken (as two workers have), computed in
    this process so the scripted gate applies: a job's guess is fixed when it is submitted, not when it runs."""
    worker, it, pending = make_worker(), iter(jobs), deque()
    while True:
        while len(pending) < 2:
            pending.append(next(it))
        yield worker(pending.popleft())


def test_a_wrong_guess_is_generated_again_and_the_batch_equals_one_process(tmp_path, monkeypatch, caplog,
                                                                           no_renders):
    factory = functools.partial(make_backend, "offline", seed=4242)
    dropped: set[str] = set()
    sequential: list[str] = []
    monkeypatch.setattr("generator.pipeline.run_gate", _scripted_gate(dropped, sequential))
    one = generate(factory, tmp_path / "one", n=2, seed=4242, command="test", candidates=1)
    assert len(dropped) == 1 and sequential[0] in dropped and len(sequential) == 3  # task 0 took two proposals

    parallel: list[str] = []
    monkeypatch.setattr("generator.pipeline.run_gate", _scripted_gate(dropped, parallel))
    monkeypatch.setattr("gendex.fanout.ordered_map", _two_ahead)
    with caplog.at_level(logging.INFO, logger="generator.pipeline"):
        batch = generate(factory, tmp_path / "batch", n=2, seed=4242, command="test", candidates=1,
                         tasks_on=Backend())
    assert "1 guess(es) redone" in caplog.text  # task 1 was first generated as if task 0's first proposal passed
    assert len(parallel) == 4  # task 0 twice, task 1 from the wrong guess, task 1 again
    assert [s.committed.name for s in batch] == [s.committed.name for s in one]
    assert [s.dropped for s in batch] == [s.dropped for s in one]
    assert _tree(tmp_path / "batch") == _tree(tmp_path / "one")


def test_batch_state_records_what_a_task_takes_from_the_tasks_before_it():
    s = BatchState(("A", "B"))
    t = s.after("C", frozenset({"X"}), None).after(None, frozenset({"W"}), None)
    assert t.names == ("A", "B", "C") and t.dropped == {"W", "X"} and t.existing() == ("A", "B", "C", "W", "X")
    assert s.names == ("A", "B") and s != t and t == BatchState(("A", "B", "C"), frozenset({"X", "W"}))


@pytest.mark.slow
def test_a_batch_on_two_worker_processes_commits_what_one_process_commits(tmp_path):
    """The real gate on 10 seeds per task, tasks on two spawned processes (about 4 min on 2 cores).
    Command: ``scripts/test.sh --slow -k two_worker_processes``."""
    factory = functools.partial(make_backend, "offline", seed=5150)
    one = generate(factory, tmp_path / "one", n=3, seed=5150, command="test")
    batch = generate(factory, tmp_path / "batch", n=3, seed=5150, command="test",
                     tasks_on=Backend("process", 2))
    assert [s.committed.name for s in batch] == [s.committed.name for s in one] and len(one) == 3
    assert _tree(tmp_path / "batch") == _tree(tmp_path / "one")
