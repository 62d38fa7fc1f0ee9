"""Evaluate a stage policy (or a random / zero baseline) on its stage env, and capture the states it succeeds in.

Evaluation episodes run like training ones: to the horizon, or to a failure; the return is summed over the whole
episode, so returns of a policy that succeeds early and one that never does compare fairly. An episode succeeds when
the goal holds at any step; its state at that first success is what the next stage starts from, and the steps up to
it are what collecting that trajectory costs. Actions are the policy's deterministic mean. Episodes run in
:func:`gendex.episode_loop.run_episode`.
"""

from __future__ import annotations

import logging
from dataclasses import asdict, dataclass

import numpy as np

from gendex.episode_loop import Hooks, Step, run_episode
from gendex.solve.policy import StagePolicy
from gendex.train.envs import make_stage_env
from gendex_envs.start_states import StartStates
from gendex_envs.task_version import TaskVersion

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class EvalResult:
    episodes: int
    successes: int
    fails: int
    mean_return: float
    """Mean undiscounted return (normalized dense reward: each step's reward is in [0, 1])."""
    env_steps: int
    """Env steps of collecting these episodes: up to the first success, else the whole episode."""

    @property
    def success_rate(self) -> float:
        return self.successes / self.episodes if self.episodes else 0.0

    def as_dict(self) -> dict:
        return asdict(self) | {"success_rate": self.success_rate}


def evaluate_stage(version: TaskVersion, stage: str | None, policy: StagePolicy | str | None, *, episodes: int = 20,
                   seed: int = 10_000, control_joint: str | None = None, start_states: StartStates | None = None,
                   capture: bool = False,
                   max_episode_steps: int | None = None) -> tuple[EvalResult, StartStates | None]:
    """Run ``episodes`` episodes (seeds ``seed``, ``seed + 1``, ...) of ``policy`` (a StagePolicy, ``"random"`` or
    ``"zero"``). With ``capture``, return the states at each episode's first success as the next stage's start
    states (None when no episode succeeded)."""
    env = make_stage_env(version, stage, control_joint=control_joint, start_states=start_states, training=True,
                         max_episode_steps=max_episode_steps)
    u = env.unwrapped
    agent = _StageAgent(policy, env.action_space.shape, np.random.default_rng(seed))
    successes = fails = steps = 0
    returns, captured = [], []
    first: int | None = None

    def on_step(step: Step) -> None:
        nonlocal first
        if first is None and step.success:
            first = step.t
            if capture:  # relabelled with the next stage by the caller
                captured.append(StartStates.capture(u, stage or "task", "policy"))

    try:
        for ep in range(episodes):
            first = None
            out = run_episode(env, agent, seed + ep, Hooks(on_step=on_step))
            steps += out.steps if first is None else first
            successes += first is not None
            fails += first is None and bool(out.info.get("fail", False))
            returns.append(out.sum_reward)
    finally:
        env.close()
    result = EvalResult(episodes=episodes, successes=successes, fails=fails, mean_return=float(np.mean(returns)),
                        env_steps=steps)
    states = StartStates.concat(captured) if captured else None
    return result, states


class _StageAgent:
    """A stage policy's deterministic mean action, or the ``"zero"`` / ``"random"`` baseline (uniform in [-1, 1],
    drawn from ``rng`` across episodes), as the loop's agent."""

    def __init__(self, policy: StagePolicy | str | None, shape: tuple[int, ...], rng: np.random.Generator):
        self.policy, self.shape, self.rng = policy, shape, rng

    def reset(self) -> None:
        pass

    def act(self, obs) -> np.ndarray:
        if isinstance(self.policy, StagePolicy):
            return self.policy.predict(obs)
        if self.policy == "zero":
            return np.zeros(self.shape, dtype=np.float32)
        return self.rng.uniform(-1.0, 1.0, self.shape).astype(np.float32)
