"""One attempt of a solver on a task: reset by seed, act until the solver finishes, gives up or the episode ends,
and say whether it succeeded and, if not, why (:class:`~gendex.solve.failure.Failure`).

The attempt is :func:`gendex.episode_loop.run_episode` with the solver as its agent
(:class:`~gendex.episode_loop.SolverAgent`); an :class:`~gendex_envs.errors.ExecutionError` of the solver ends it as
a failed attempt. ``gendex collect`` records its attempts through ``hooks`` (a recorder and camera frames); the
generator's solvability gate runs it bare.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace

from gendex.episode_loop import NO_HOOKS, Hooks, SolverAgent, run_episode, succeeded
from gendex.solve.failure import Failure
from gendex_envs.errors import ExecutionError

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class AttemptOutcome:
    succeeded: bool
    steps: int
    failure: Failure | None
    """Why it failed (None when it succeeded)."""


def run_attempt(env, solver, seed: int, hooks: Hooks = NO_HOOKS) -> AttemptOutcome:
    """Run ``solver`` on ``env`` from ``env.reset(seed=seed)`` until it returns None, raises ExecutionError or the
    episode ends; ``hooks`` (:class:`~gendex.episode_loop.Hooks`, its ``catch`` replaced) see the episode."""
    out = run_episode(env, SolverAgent(solver, env), seed, replace(hooks, catch=(ExecutionError,)))
    failure: Failure | None = None
    if out.error is not None:  # the solver gave up on this attempt: a failed attempt, not a crash
        failure = Failure.of_error(out.error)
        log.info("attempt with seed %d: %s", seed, failure)
    ok = failure is None and succeeded(out.info)
    if failure is None and not ok:
        failure = Failure.of_ending(solver, env, out.terminated, out.truncated)
    return AttemptOutcome(ok, out.steps, failure)


__all__ = ["AttemptOutcome", "run_attempt", "succeeded"]
