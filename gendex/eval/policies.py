"""The built-in policies of ``gendex eval --policy SPEC`` and how a SPEC becomes a policy.

``random``
    uniform actions of the action space, drawn from the episode's own randomness (``env.np_random``);
``hold``
    keeps every joint target where it is (succeeds only where the task is solved at reset);
``oracle``
    the planning stage executor (:mod:`gendex.solve.executor`: planned arm motion, synthesized grasps, articulated
    primitives and the task's trained stage policies where it has them) reading the simulator: an upper reference,
    not a learned policy; once it has finished or given up it holds;
``module:factory``
    ``factory()`` from an importable module, returning an object with ``reset()`` and ``act(obs)``.

(``bc:PATH``, a behaviour-cloning checkpoint, is resolved by the command line, which may import the learners.)
"""

from __future__ import annotations

import importlib
import logging
from collections.abc import Callable

import gymnasium as gym
import numpy as np

from gendex.episode_loop import SolverAgent
from gendex_envs.errors import ExecutionError, GenDexError

log = logging.getLogger(__name__)

BUILTIN = ("random", "hold", "oracle")


class PolicySpecError(GenDexError, ValueError):
    """A ``--policy`` value that names no policy."""


class _Bound:
    def bind(self, env: gym.Env) -> None:
        self.env = env

    def _hold(self) -> np.ndarray:
        return self.env.unwrapped.agent.controller.free_targets()[0].cpu().numpy()


class RandomPolicy(_Bound):
    kind = "baseline"

    def reset(self) -> None:
        self.rng = np.random.default_rng(int(self.env.unwrapped.np_random.integers(2**31)))

    def act(self, obs) -> np.ndarray:
        space = self.env.action_space
        return self.rng.uniform(space.low, space.high).astype(np.float32)


class HoldPolicy(_Bound):
    kind = "baseline"

    def reset(self) -> None:
        pass

    def act(self, obs) -> np.ndarray:
        return self._hold()


class OraclePolicy(_Bound):
    kind = "oracle"

    def bind(self, env: gym.Env) -> None:
        from gendex.solve import SOLVERS

        super().bind(env)
        # the executor drives the gym.make env under LeRobotObservation and reads it, not the observation
        self.solver = SolverAgent(SOLVERS["stages"](), env.env)

    def reset(self) -> None:
        self.solver.reset()
        self.done = False

    def act(self, obs) -> np.ndarray:
        if not self.done:
            try:
                action = self.solver.act(None)
            except ExecutionError as exc:
                log.info("oracle gave up: %s", exc)
                action = None
            if action is not None:
                return np.asarray(action, dtype=np.float32)
            self.done = True
        return self._hold()


def resolve_policy(spec: str) -> Callable[[], object]:
    """A factory of the policy ``spec`` names (see the module docstring)."""
    if spec in BUILTIN:
        return {"random": RandomPolicy, "hold": HoldPolicy, "oracle": OraclePolicy}[spec]
    if ":" in spec and not spec.startswith("bc:"):
        module, _, name = spec.partition(":")
        try:
            factory = getattr(importlib.import_module(module), name)
        except (ImportError, AttributeError) as exc:
            raise PolicySpecError(f"--policy {spec!r}: cannot import {name!r} from {module!r} ({exc})") from exc
        if not callable(factory):
            raise PolicySpecError(f"--policy {spec!r}: {module}.{name} is not callable")
        return factory
    raise PolicySpecError(f"--policy {spec!r} is not one of {list(BUILTIN)}, bc:PATH or module:factory")


__all__ = ["BUILTIN", "HoldPolicy", "OraclePolicy", "PolicySpecError", "RandomPolicy", "resolve_policy"]
