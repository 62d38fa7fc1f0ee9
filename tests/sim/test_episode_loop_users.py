"""Collection, the solvability gate, evaluation (the runner BC checkpoints are evaluated with), the ablation's
whole-task evaluation, stage-policy evaluation and start-state collection all run their episodes through the one
loop, :func:`gendex.episode_loop.run_episode`: every episode each of them runs is an outcome the loop made.

Cheap stand-ins (hold for two steps) replace the stage executor where a user runs it."""

from __future__ import annotations

import functools
from pathlib import Path

import pytest

import gendex.episode_loop as loop
from gendex.solve.baselines import HoldSolver

TASK = "GenDex/PutAppleBowl-v1"


@pytest.fixture
def outcomes(monkeypatch):
    """Every EpisodeOutcome the loop makes, in order: (seed, steps, ended_by)."""
    made: list[tuple[int, int, str]] = []

    class Recorded(loop.EpisodeOutcome):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            made.append((self.seed, self.steps, self.ended_by))

    monkeypatch.setattr(loop, "EpisodeOutcome", Recorded)
    return made


class HoldTwo(HoldSolver):
    """The hold baseline for two steps, with the executor's ``finished`` (start-state collection reads it)."""

    def __init__(self, **_kwargs):
        super().__init__(steps=2)
        self.finished = False


def test_collect_and_the_gate_run_the_shared_loop(outcomes, monkeypatch):
    import gendex.solve
    from gendex.data.collector import CollectConfig, attempt_once
    from gendex.solve import SOLVER_ENV_KWARGS
    from gendex_envs.registry import make_env, resolve_task
    from generator.steps.gate import measure, null_solves

    cfg = CollectConfig(task_id=TASK, num_success=1, out=Path("."), formats=(), seed=3, **SOLVER_ENV_KWARGS["hold"])
    episode, steps, failure = attempt_once(cfg, functools.partial(HoldSolver, steps=2), 3)
    assert outcomes == [(3, 2, "agent")] and steps == 2 and episode.action.shape[0] == 2

    outcomes.clear()
    monkeypatch.setitem(gendex.solve.SOLVERS, "stages", lambda: HoldSolver(steps=2))
    gate = measure(resolve_task(TASK).root, seeds=[5, 6])
    assert (gate.attempts, gate.successes) == (2, 0) and outcomes == [(5, 2, "agent"), (6, 2, "agent")]

    outcomes.clear()
    env = make_env(resolve_task(TASK), obs_mode="state", **SOLVER_ENV_KWARGS["stages"])
    try:
        assert not null_solves(env, 8, 2)
    finally:
        env.close()
    assert outcomes == [(8, 2, "agent")]


def test_evaluation_and_training_run_the_shared_loop(outcomes, monkeypatch, tmp_path):
    import gendex.train.ablate as ablate
    import gendex.train.start_states as start_states
    from gendex.eval.policies import HoldPolicy
    from gendex.eval.runner import evaluate_task
    from gendex.train.evaluate import evaluate_stage
    from gendex_envs.errors import StageError
    from gendex_envs.registry import resolve_task
    from gendex_envs.task_version import Artifacts

    rows = evaluate_task(TASK, HoldPolicy, [3, 4], max_episode_steps=2)
    assert [(r.seed, r.length) for r in rows] == [(3, 2), (4, 2)]
    assert outcomes == [(3, 2, "truncated"), (4, 2, "truncated")]

    version = resolve_task(TASK)
    outcomes.clear()
    monkeypatch.setattr(ablate, "StageExecutor", HoldTwo)
    assert ablate.evaluate_executor(version, Artifacts(tmp_path), 2, seed=10, policy_stages="rl") == (0, 4)
    assert outcomes == [(10, 2, "agent"), (11, 2, "agent")]

    outcomes.clear()
    result, _ = evaluate_stage(version, version.spec.stages[0].name, "zero", episodes=1, seed=20, max_episode_steps=2)
    assert result.episodes == 1 and outcomes == [(20, 2, "truncated")]

    outcomes.clear()
    monkeypatch.setattr(start_states, "StageExecutor", HoldTwo)
    with pytest.raises(StageError, match="never finished"):
        start_states.collect_executor_states(version, 1, 1, seed=30, max_attempts=1)
    assert outcomes == [(30, 2, "agent")]
