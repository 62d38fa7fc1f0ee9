"""Evaluate a stage policy (or a random / zero baseline) on its stage env, and capture the states it succeeds in.

Evaluation episodes run like training ones: to the horizon, or to a failure; the return is summed over the whole
episode, so returns of a policy that succeeds early and one that never does compare fairly. An episode succeeds when
the goal holds at any step; its state at that first success is what the next stage starts from, and the steps up to
it are what collecting that trajectory costs. Actions are the policy's deterministic mean.
"""

from __future__ import annotations

import logging
from dataclasses import asdict, dataclass

import numpy as np

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
    rng = np.random.default_rng(seed)
    successes = fails = steps = 0
    returns, captured = [], []
    try:
        for ep in range(episodes):
            obs, _ = env.reset(seed=seed + ep)
            total, done, first, t = 0.0, False, None, 0
            while not done:
                if isinstance(policy, StagePolicy):
                    action = policy.predict(obs)
                elif policy == "zero":
                    action = np.zeros(env.action_space.shape, dtype=np.float32)
                else:
                    action = rng.uniform(-1.0, 1.0, env.action_space.shape).astype(np.float32)
                obs, reward, terminated, truncated, info = env.step(action)
                total += float(reward)
                t += 1
                if first is None and bool(info["success"]):
                    first = t
                    if capture:  # relabelled with the next stage by the caller
                        captured.append(StartStates.capture(u, stage or "task", "policy"))
                done = terminated or truncated
            steps += t if first is None else first
            successes += first is not None
            fails += first is None and bool(info.get("fail", False))
            returns.append(total)
    finally:
        env.close()
    result = EvalResult(episodes=episodes, successes=successes, fails=fails, mean_return=float(np.mean(returns)),
                        env_steps=steps)
    states = StartStates.concat(captured) if captured else None
    return result, states
