"""The one episode loop every application runs: :func:`run_episode` ``(env, agent, seed, hooks)``.

Solver attempts (``gendex collect`` and the solvability gate, through :func:`gendex.solve.attempt.run_attempt`),
policy evaluation (``gendex eval``, BC checkpoints included: :mod:`gendex.eval.runner`), the ablation's whole-task
evaluation and stage-policy evaluation (:mod:`gendex.train`) and start-state collection all run their episodes
here. What differs between them is an agent and hooks:

* an **agent** (:class:`Agent`): ``reset()`` at the start of every episode, ``act(obs)`` every step (None: the agent
  is done and the episode ends), and optionally ``bind(env)``, called once per env by whoever makes the env
  (:func:`bind`). :class:`SolverAgent` makes a solver (:class:`gendex.solve.baselines.Solver`, which reads the env)
  an agent;
* **hooks** (:class:`Hooks`): what turns an action into the one stepped, what sees the reset and every step
  (a recorder, camera frames, videos), when to stop early (at success), and which of the agent's errors end the
  episode as a failure instead of propagating.

One episode: ``env.reset(seed=int(seed))``, ``agent.reset()``, ``hooks.on_reset(obs, info)``; then, until the agent
returns None, the episode terminates or is truncated, or ``hooks.stop`` says so: ``action = agent.act(obs)``,
``hooks.prepare(action)``, ``env.step``, ``hooks.on_step(step)``. The loop reads the env's ``success`` and the
reward of every step into the :class:`EpisodeOutcome`; it changes nothing else.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import gymnasium as gym
import numpy as np


class Agent(Protocol):
    """What acts in an episode. May also have ``bind(env)`` (see :func:`bind`)."""

    def reset(self) -> None: ...

    def act(self, obs: Any) -> Any: ...


def bind(agent: Agent, env: gym.Env) -> None:
    """Call ``agent.bind(env)`` where the agent has one (once per env, before its first episode there)."""
    if hasattr(agent, "bind"):
        agent.bind(env)


class SolverAgent:
    """A solver as an :class:`Agent`: it reads the env it is bound to, so ``reset()`` passes it no observation
    (``solver.reset(env, None)``) and ``act(obs)`` is ``solver.act(env, obs)``."""

    def __init__(self, solver, env: gym.Env | None = None):
        self.solver = solver
        self.env = env

    def bind(self, env: gym.Env) -> None:
        self.env = env

    def reset(self) -> None:
        self.solver.reset(self.env, None)

    def act(self, obs: Any) -> Any:
        return self.solver.act(self.env, obs)


@dataclass(frozen=True)
class Step:
    """One env step as the hooks see it."""

    t: int
    """Steps taken in the episode, this one included (1 for the first)."""
    action: Any
    """The action stepped (after ``hooks.prepare``)."""
    obs: Any
    reward: Any
    terminated: bool
    truncated: bool
    info: dict
    success: bool
    """The env's ``success`` after this step."""


@dataclass(frozen=True)
class Hooks:
    """What a user of :func:`run_episode` adds to the loop (every field optional)."""

    prepare: Callable[[Any], Any] | None = None
    """Turns the agent's action into the one stepped (a recorder's float32 ``[A]``)."""
    on_reset: Callable[[Any, dict], None] | None = None
    """Sees the reset's ``(obs, info)``, after ``agent.reset()``."""
    on_step: Callable[[Step], None] | None = None
    """Sees every step, before the loop decides whether to go on."""
    stop: Callable[[Step], bool] | None = None
    """True ends the episode after this step (an evaluation that stops at success)."""
    catch: tuple[type[BaseException], ...] = ()
    """Exceptions of ``agent.act`` that end the episode as a failure (kept in :attr:`EpisodeOutcome.error`) instead
    of propagating; ``agent.reset`` is not guarded: an agent that cannot start is a setup error."""
    stop_at_end: bool = True
    """False: step on after the episode terminated or was truncated, until the agent is done (start-state
    collection judges the state the agent leaves)."""


NO_HOOKS = Hooks()


@dataclass(frozen=True)
class EpisodeOutcome:
    """What one run of :func:`run_episode` gave."""

    seed: int
    steps: int
    """Env steps taken."""
    success_once: bool
    """The env reported success after some step."""
    success_at_end: bool
    """The env reported success after the last step (False when no step was taken)."""
    sum_reward: float
    max_reward: float
    """Largest step reward (0.0 when no step was taken)."""
    terminated: bool
    truncated: bool
    info: dict
    """The last step's info (the reset's when no step was taken)."""
    ended_by: str
    """``agent`` (it returned None), ``terminated``, ``truncated``, ``stop`` (``hooks.stop``) or ``error``."""
    error: BaseException | None = None
    """The exception of ``hooks.catch`` the agent raised (``ended_by == "error"``)."""


def succeeded(info: dict) -> bool:
    """The env's ``success`` of a single-env step info (False when it has none)."""
    value = info.get("success", False)
    return bool(np.asarray(value.cpu() if hasattr(value, "cpu") else value).reshape(-1)[0])


def run_episode(env: gym.Env, agent: Agent, seed: int, hooks: Hooks = NO_HOOKS) -> EpisodeOutcome:
    """Run one episode of ``agent`` on a one-env ``env`` from ``env.reset(seed=int(seed))`` (module docstring)."""
    obs, info = env.reset(seed=int(seed))
    agent.reset()
    if hooks.on_reset is not None:
        hooks.on_reset(obs, info)
    steps, once, end, total, best = 0, False, False, 0.0, -math.inf
    terminated = truncated = False
    ended_by, error = "agent", None
    while True:
        try:
            action = agent.act(obs)
        except hooks.catch as exc:
            ended_by, error = "error", exc
            break
        if action is None:
            break
        if hooks.prepare is not None:
            action = hooks.prepare(action)
        obs, reward, terminated, truncated, info = env.step(action)
        steps += 1
        r = float(reward)
        total += r
        best = max(best, r)
        end = succeeded(info)
        once = once or end
        step = Step(steps, action, obs, reward, bool(terminated), bool(truncated), info, end)
        if hooks.on_step is not None:
            hooks.on_step(step)
        if hooks.stop_at_end and (terminated or truncated):
            ended_by = "terminated" if terminated else "truncated"
            break
        if hooks.stop is not None and hooks.stop(step):
            ended_by = "stop"
            break
    return EpisodeOutcome(int(seed), steps, once, end, total, best if steps else 0.0, bool(terminated),
                          bool(truncated), info, ended_by, error)


__all__ = ["NO_HOOKS", "Agent", "EpisodeOutcome", "Hooks", "SolverAgent", "Step", "bind", "run_episode",
           "succeeded"]
