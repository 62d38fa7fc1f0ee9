"""One attempt of a solver on a task: reset by seed, act until the solver finishes, gives up or the episode ends,
and say whether it succeeded and, if not, why (:class:`~gendex.solve.failure.Failure`).

``gendex collect`` records its attempts through this loop (its ``begin`` / ``step`` hooks record the episode); the
generator's solvability gate runs it bare.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from gendex.solve.failure import Failure
from gendex_envs.errors import ExecutionError

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class AttemptOutcome:
    succeeded: bool
    steps: int
    failure: Failure | None
    """Why it failed (None when it succeeded)."""


def succeeded(info: dict) -> bool:
    """The env's ``success`` of a single-env step info."""
    value = info.get("success", False)
    return bool(np.asarray(value.cpu() if hasattr(value, "cpu") else value).reshape(-1)[0])


def run_attempt(env, solver, seed: int, begin: Callable[[int], tuple[Any, dict]] | None = None,
                step: Callable[[Any], tuple] | None = None,
                on_obs: Callable[[Any], None] | None = None) -> AttemptOutcome:
    """Run ``solver`` on ``env`` from ``env.reset(seed=seed)`` (or ``begin(seed)``), stepping with ``env.step`` (or
    ``step``); ``on_obs`` sees every observation."""
    obs, info = begin(seed) if begin is not None else env.reset(seed=seed)
    step = step if step is not None else env.step
    solver.reset(env, obs)
    if on_obs is not None:
        on_obs(obs)
    failure: Failure | None = None
    terminated = truncated = False
    steps = 0
    while True:
        try:
            action = solver.act(env, obs)
        except ExecutionError as exc:  # the solver gave up on this attempt: a failed attempt, not a crash
            failure = Failure.of_error(exc)
            log.info("attempt with seed %d: %s", seed, failure)
            break
        if action is None:
            break
        obs, _, terminated, truncated, info = step(action)
        steps += 1
        if on_obs is not None:
            on_obs(obs)
        if terminated or truncated:
            break
    ok = failure is None and succeeded(info)
    if failure is None and not ok:
        failure = Failure.of_ending(solver, env, bool(terminated), bool(truncated))
    return AttemptOutcome(ok, steps, failure)


__all__ = ["AttemptOutcome", "run_attempt", "succeeded"]
