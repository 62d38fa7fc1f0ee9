"""Run a policy on a task for a list of seeds and record what happened in each episode.

A policy is any object with ``reset()`` and ``act(obs) -> action``: ``obs`` is what
:class:`~gendex_envs.observation.LeRobotObservation` gives (the features of GenDex datasets, by the same names), the
action one of the env's default action space (absolute joint targets, ``pd_joint_pos``). A policy that needs the
simulator itself (the planner oracle) may also have ``bind(env)``, called once with the env.

Conventions (ManiSkill's, LeRobot's): every episode is reset with its own seed and runs until the task's time limit
or termination (no early stop at success, no partial resets); ``success_once`` (success at any step) and
``success_at_end`` (at the last step) are both recorded, with the summed and the largest reward. An episode whose
policy raises, returns a non-finite action or one outside the action space fails with the reason recorded, and the
evaluation goes on. Envs are made with :data:`~gendex_envs.registry.HISTORY_FREE`, so an episode depends only on the
task, the seed and the policy.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any, Protocol

import gymnasium as gym
import numpy as np

from gendex.episode_loop import Hooks, bind, run_episode
from gendex_envs.cameras import SENSOR_CAMERAS
from gendex_envs.observation import LeRobotObservation
from gendex_envs.registry import HISTORY_FREE

log = logging.getLogger(__name__)

ACTION_TOL = 1e-4
"""How far (in the action's units) an action may stray outside the action space before the episode fails."""


class Policy(Protocol):
    """An :class:`gendex.episode_loop.Agent` acting on LeRobotObservation's dict, with the env's action space."""

    def reset(self) -> None: ...

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray: ...


@dataclass(frozen=True)
class EpisodeResult:
    task: str
    seed: int
    success_once: bool
    success_at_end: bool
    sum_reward: float
    max_reward: float
    length: int
    """Env steps taken."""
    seconds: float
    failure: str | None = None
    """Why the policy made the episode fail (it raised, or gave a NaN or out-of-range action); None otherwise."""
    video: str | None = None
    """The episode's video file, when it was recorded."""

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def make_eval_env(task: str, env_kwargs: dict | None = None, max_episode_steps: int | None = None,
                  render: bool = False) -> gym.Env:
    """The env an evaluation runs in: ``gym.make(task, **env_kwargs, **HISTORY_FREE)`` under LeRobotObservation
    (``render``: with ``render_mode="rgb_array"``, for episode videos)."""
    kwargs = {**(env_kwargs or {}), **HISTORY_FREE}
    if render:
        kwargs["render_mode"] = "rgb_array"
    if max_episode_steps is not None:
        kwargs["max_episode_steps"] = max_episode_steps
    return LeRobotObservation(gym.make(task, **kwargs))


OBSERVATION_KWARGS = {"obs_mode": ("state", "rgb"), "sensor_resolution": range(8, 513), "sensors": SENSOR_CAMERAS}
"""What a policy may ask the evaluation env to observe (``policy.observation_kwargs``): cameras (``sensors``: a list
of their names, each rendered at every step) and their size. These change what the env renders, never its physics;
nothing else a policy asks for reaches ``gym.make``."""


def observation_kwargs(policy) -> dict:
    """The policy's ``observation_kwargs`` (e.g. a pixel policy's camera rendering), checked against
    :data:`OBSERVATION_KWARGS`; ValueError naming what is not allowed."""
    asked = getattr(policy, "observation_kwargs", None) or {}

    def allowed(key, value) -> bool:
        if key == "sensors":
            return (isinstance(value, list | tuple) and 0 < len(value) <= len(SENSOR_CAMERAS)
                    and all(type(v) is str and v in SENSOR_CAMERAS for v in value) and len(set(value)) == len(value))
        return key in OBSERVATION_KWARGS and type(value) is not bool and value in OBSERVATION_KWARGS[key]

    bad = {k: v for k, v in asked.items() if not allowed(k, v)}
    if bad:
        raise ValueError(f"the policy asks the env for {bad}; a policy may only set obs_mode (state, rgb), "
                         f"sensor_resolution (8..512) and sensors (a list of {list(SENSOR_CAMERAS)})")
    return dict(asked)


def _check_action(action: Any, space: gym.spaces.Box) -> tuple[np.ndarray | None, str | None]:
    try:
        a = np.asarray(action, dtype=np.float32).reshape(space.shape)
    except (TypeError, ValueError) as exc:
        return None, f"the action {np.shape(action)} is not of the action space's shape {space.shape} ({exc})"
    if not np.all(np.isfinite(a)):
        return None, "the action holds NaN or inf"
    low, high = space.low, space.high
    worst = float(np.max(np.maximum(low - a, a - high)))
    if worst > ACTION_TOL:
        i = int(np.argmax(np.maximum(low - a, a - high)))
        return None, (f"action[{i}] = {a[i]:.4g} is outside the action space [{low[i]:.4g}, {high[i]:.4g}] "
                      f"by {worst:.3g}")
    return np.clip(a, low, high), None


class PolicyFault(Exception):
    """The policy made its episode fail (it raised, or gave a NaN or out-of-range action); the message says how."""


class _Guarded:
    """The user's policy as the loop's agent: whatever it raises, and an action it gives that is not finite or not
    in the action space, becomes a :class:`PolicyFault` that fails the episode (an action is clipped into the
    space)."""

    def __init__(self, policy: Policy, space: gym.spaces.Box):
        self.policy, self.space = policy, space

    def reset(self) -> None:
        self.fault: str | None = None
        try:
            self.policy.reset()
        except Exception as exc:  # the policy is the user's code: any error fails this episode only
            self.fault = f"the policy's reset() raised {type(exc).__name__}: {exc}"

    def act(self, obs) -> np.ndarray:
        if self.fault is not None:
            raise PolicyFault(self.fault)
        try:
            raw = self.policy.act(obs)
        except Exception as exc:  # as above
            raise PolicyFault(f"the policy's act() raised {type(exc).__name__}: {exc}") from exc
        action, failure = _check_action(raw, self.space)
        if failure is not None:
            raise PolicyFault(failure)
        return action


def evaluate_episode(env: gym.Env, policy: Policy, task: str, seed: int,
                     frames: list[np.ndarray] | None = None) -> EpisodeResult:
    """One episode of ``policy`` from ``env.reset(seed=seed)`` until the time limit or termination
    (:func:`gendex.episode_loop.run_episode`; ``frames``: a list the rendered frame of every step is appended to)."""
    t0 = time.perf_counter()
    hooks = Hooks(catch=(PolicyFault,))
    if frames is not None:
        hooks = Hooks(on_reset=lambda obs, info: frames.append(np.asarray(env.render())),
                      on_step=lambda step: frames.append(np.asarray(env.render())), catch=(PolicyFault,))
    out = run_episode(env, _Guarded(policy, env.action_space), seed, hooks)
    failure = None if out.error is None else str(out.error)
    if failure is not None:
        log.info("%s seed %d: %s", task, seed, failure)
    return EpisodeResult(task, int(seed), out.success_once, out.success_at_end and failure is None, out.sum_reward,
                         out.max_reward, out.steps, round(time.perf_counter() - t0, 3), failure)


def evaluate_task(task: str, make_policy: Callable[[], Policy], seeds: Iterable[int], *,
                  env_kwargs: dict | None = None, max_episode_steps: int | None = None,
                  progress: Callable[[EpisodeResult], None] | None = None, videos: int = 0,
                  video_dir: Path | None = None) -> list[EpisodeResult]:
    """Run a fresh ``make_policy()`` on ``task`` for every seed (one env, reused: it is rebuilt at each reset);
    the first ``videos`` episodes are also written as ``<video_dir>/<task name>_<seed>.mp4``."""
    from gendex_envs.video import encode

    policy = make_policy()
    env = make_eval_env(task, {**(env_kwargs or {}), **observation_kwargs(policy)}, max_episode_steps,
                        render=videos > 0)
    try:
        try:
            bind(policy, env)
        except Exception as exc:  # the policy cannot act here: each episode fails with the reason
            why = f"policy bind raised {type(exc).__name__}: {exc}"
            log.info("%s: %s", task, why)
            out = [EpisodeResult(task, int(seed), False, False, 0.0, 0.0, 0, 0.0, why) for seed in seeds]
            for r in out:
                if progress is not None:
                    progress(r)
            return out
        out = []
        for k, seed in enumerate(seeds):
            frames = [] if k < videos and video_dir is not None else None
            r = evaluate_episode(env, policy, task, seed, frames)
            if frames:
                video_dir.mkdir(parents=True, exist_ok=True)
                path = video_dir / f"{task.split('/')[-1]}_{seed}.mp4"
                encode(np.stack([f.reshape(f.shape[-3:]) for f in frames]).astype(np.uint8), path,
                       int(env.unwrapped.control_freq))
                r = replace(r, video=str(path))
            out.append(r)
            if progress is not None:
                progress(r)
        return out
    finally:
        env.close()


__all__ = ["ACTION_TOL", "OBSERVATION_KWARGS", "EpisodeResult", "Policy", "PolicyFault", "evaluate_episode",
           "evaluate_task", "make_eval_env", "observation_kwargs"]
