"""The solver interface and two baselines: hold still, and uniform random actions."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import gymnasium as gym
import numpy as np


class Solver(Protocol):
    """Drives one episode: ``reset`` after the env reset, then ``act`` until it returns None or the episode ends.

    A solver reads the env: ``obs`` may be None (:class:`gendex.episode_loop.SolverAgent`, how the episode loop runs a
    solver, resets it without one)."""

    name: str

    def reset(self, env: gym.Env, obs) -> None: ...

    def act(self, env: gym.Env, obs) -> np.ndarray | None: ...


@dataclass
class HoldSolver:
    """Baseline: holds every joint target for ``steps`` steps (succeeds only where the scene already does)."""

    steps: int = 10
    name: str = "hold"

    def reset(self, env: gym.Env, obs) -> None:
        self._left = self.steps

    def act(self, env: gym.Env, obs) -> np.ndarray | None:
        if self._left == 0:
            return None
        self._left -= 1
        ctrl = env.unwrapped.agent.controller
        if ctrl.config.use_delta:
            return np.zeros(env.action_space.shape, dtype=np.float32)
        return ctrl.free_targets()[0].cpu().numpy()


@dataclass
class RandomSolver:
    """Baseline: uniform random actions for ``steps`` steps, seeded per episode from the env's RNG."""

    steps: int = 50
    name: str = "random"

    def reset(self, env: gym.Env, obs) -> None:
        self._left = self.steps
        self._rng = np.random.default_rng(int(env.unwrapped.np_random.integers(2**31)))

    def act(self, env: gym.Env, obs) -> np.ndarray | None:
        if self._left == 0:
            return None
        self._left -= 1
        space = env.action_space
        return self._rng.uniform(space.low, space.high).astype(np.float32)
