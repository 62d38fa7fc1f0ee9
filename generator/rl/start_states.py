"""Start states of a stage: the states in which the previous stage succeeded, collected with the stage executor.

The executor runs stages ``0 .. K-1`` (motion planning, scripted primitives, or trained policies where the policy
folder has them) and stops where stage K would begin; the state is kept when the executor finished those stages and
stage K-1's own ``evaluate`` reports success.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

from tqdm import tqdm

from gendex_envs.errors import ExecutionError, StageError
from gendex_envs.reward_module import load_reward_module
from gendex_envs.solve.executor import StageExecutor
from gendex_envs.stage import StartStates, resolve_stage, stage_reward_path

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Collected:
    states: StartStates
    attempts: int
    env_steps: int


def collect_executor_states(task_dir: str | Path, stage: str | int, n: int, *, seed: int = 0,
                            policy_dir: Path | None = None, max_attempts: int | None = None,
                            progress: bool = False) -> Collected:
    """Up to ``n`` states at the success of the stage before ``stage``; :class:`StageError` when none is found
    in ``max_attempts`` episodes (default ``3 n``)."""
    from gendex_envs.registry import make_task_env  # noqa: PLC0415

    env = make_task_env(str(task_dir), control_mode="pd_joint_pos", control_joint="both", max_episode_steps=10_000)
    u = env.unwrapped
    index, spec = resolve_stage(u.task_spec, stage)
    if index == 0:
        env.close()
        raise StageError(f"stage {spec.name!r} is the first stage: it starts from the task's reset states")
    prev = u.task_spec.stages[index - 1]
    judge = load_reward_module(stage_reward_path(task_dir, prev.name))
    ex = StageExecutor(policy_dir=policy_dir, stop_before=index)
    rows, steps, attempts = [], 0, 0
    max_attempts = 3 * n if max_attempts is None else max_attempts
    bar = tqdm(total=n, desc=f"start states of {spec.name}", disable=not progress, leave=False)
    try:
        while len(rows) < n and attempts < max_attempts:
            obs, _ = env.reset(seed=seed + attempts)
            attempts += 1
            ex.reset(env, obs)
            try:
                while (action := ex.act(env, obs)) is not None:
                    obs, _, _, _, _ = env.step(action)
                    steps += 1
            except ExecutionError as e:
                log.debug("attempt %d: %s", attempts, e)
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
