"""Start states of a stage: the states in which the previous stage succeeded, collected with the stage executor.

The executor runs stages ``0 .. K-1`` (motion planning, scripted primitives, or trained policies where the policy
folder has them) and stops where stage K would begin; the state is kept when the executor finished those stages and
stage K-1's own ``evaluate`` reports success. Each attempt is one :func:`gendex.episode_loop.run_episode` that runs on
past the task's own termination and time limit: only where the executor stops counts.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

from tqdm import tqdm

from gendex.episode_loop import Hooks, SolverAgent, run_episode
from gendex.solve.executor import StageExecutor
from gendex_envs.errors import ExecutionError, StageError
from gendex_envs.start_states import StartStates
from gendex_envs.task_version import Artifacts, TaskVersion

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Collected:
    states: StartStates
    attempts: int
    env_steps: int


def collect_executor_states(version: TaskVersion, stage: str | int, n: int, *, seed: int = 0,
                            policy_sources: Sequence[Artifacts] | None = None, max_attempts: int | None = None,
                            progress: bool = False) -> Collected:
    """Up to ``n`` states at the success of the stage before ``stage``; :class:`StageError` when none is found
    in ``max_attempts`` episodes (default ``3 n``). ``policy_sources``: where earlier stages' trained policies
    come from (default: the version's own)."""
    from gendex_envs.registry import make_env

    index, spec = version.stage(stage)
    if index == 0:
        raise StageError(f"stage {spec.name!r} is the first stage: it starts from the task's reset states")
    env = make_env(version, control_mode="pd_joint_pos", control_joint="both", max_episode_steps=10_000)
    u = env.unwrapped
    prev = u.task_spec.stages[index - 1]
    judge = version.judge(prev.name)
    ex = StageExecutor(policy_sources=policy_sources, stop_before=index)
    agent = SolverAgent(ex, env)
    hooks = Hooks(catch=(ExecutionError,), stop_at_end=False)  # judged where the executor stops, not by the task
    rows, steps, attempts = [], 0, 0
    max_attempts = 3 * n if max_attempts is None else max_attempts
    bar = tqdm(total=n, desc=f"start states of {spec.name}", disable=not progress, leave=False)
    try:
        while len(rows) < n and attempts < max_attempts:
            out = run_episode(env, agent, seed + attempts, hooks)
            attempts += 1
            steps += out.steps
            if out.error is not None:
                log.debug("attempt %d: %s", attempts, out.error)
                continue
            if ex.finished and bool(judge.evaluate(u)["success"][0]):
                rows.append(StartStates.capture(u, spec.name, "executor"))
                bar.update(1)
    finally:
        bar.close()
        env.close()
    if not rows:
        raise StageError(f"the executor never finished stage {prev.name!r} with its goal met in {attempts} attempts: "
                         f"stage {spec.name!r} has no start states")
    log.info("start states of %s: %d of %d attempts, %d env steps", spec.name, len(rows), attempts, steps)
    return Collected(StartStates.concat(rows), attempts, steps)
