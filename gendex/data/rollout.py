"""Record a rollout of a GenDex env into an :class:`~gendex.data.episode.Episode`, replay it, and the
env-state helpers both need.

Env state: ``env.unwrapped.get_state()`` flattens ``get_state_dict()`` — the non-static actors (13 values each: pose,
linear and angular velocity), the articulations (root pose and velocities, qpos, qvel) and then the controller state.
GenDex's controller always reports its drive targets (``controller/target_qpos``: frozen joints hold their target, and
``pd_joint_delta_pos`` adds each action to the previous target), so the vector holds everything an action's effect
depends on except PhysX's internal caches (contacts, solver warm start) and the task's per-episode bookkeeping
(reset positions, success streak, elapsed steps), which a reset with the recorded seed rebuilds. ManiSkill's own
``set_state`` drops the controller part; ``TaskEnv.set_state`` (used by :func:`set_flat_env_state`) restores it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np
import torch

from gendex.data.episode import Episode, EpisodeError
from gendex.episode_loop import Hooks, Step
from gendex_envs import observation


class ReplayError(EpisodeError):
    """An episode cannot be replayed: its control mode, action size or reset state differs from the recording."""


@dataclass(frozen=True)
class ReplayResult:
    """How a replay of recorded actions compares with the recording."""

    episode_id: int
    steps: int
    success_recorded: bool
    """Recorded success after the last action."""
    success_replayed: bool
    max_object_pos_err_m: float
    """Largest distance between a replayed and a recorded task-object position after the last action."""
    max_env_state_err: float
    """Largest absolute difference of any flat env-state entry (positions, velocities, targets) over all steps;
    with ``use_env_states`` a one-step error, dominated by contact velocities."""
    object_pos_err_by_name: dict[str, float] = field(hash=False)
    success_steps_differing: int = 0
    """Steps whose replayed success flag differs from the recorded one."""

    def reproduced(self, pos_tol_m: float = 1e-3) -> bool:
        """Same success flag at every step, and every object within ``pos_tol_m`` of its recorded end position."""
        return (self.success_steps_differing == 0 and self.success_recorded == self.success_replayed
                and self.max_object_pos_err_m <= pos_tol_m)


def _base(env: gym.Env):
    u = env.unwrapped
    if u.num_envs != 1:
        raise EpisodeError(f"episodes are recorded from one env, got num_envs={u.num_envs}")
    return u


def _scalar(x) -> float | bool:
    """Python scalar of a value from a num_envs=1 env (python scalar, numpy array or torch tensor of one element)."""
    if isinstance(x, torch.Tensor):
        x = x.detach().cpu().numpy()
    return np.asarray(x).reshape(-1)[0].item()


def state_layout(env: gym.Env) -> dict[str, slice]:
    """Where each entry of ``get_state_dict()`` lies in the flat state: ``"actors/<name>"``,
    ``"articulations/<name>"``, ``"controller/<key>"`` (nested controllers: ``"controller/<uid>/<key>"``) -> slice."""
    u = _base(env)
    layout: dict[str, slice] = {}
    start = 0

    def walk(d: dict, prefix: str):
        nonlocal start
        for key, value in d.items():
            path = f"{prefix}{key}"
            if isinstance(value, dict):
                walk(value, path + "/")
                continue
            size = int(value.shape[-1]) if getattr(value, "ndim", 0) == 2 else 1
            layout[path] = slice(start, start + size)
            start += size

    walk(u.get_state_dict(), "")
    total = int(u.get_state().shape[-1])
    if start != total:  # our reading of ManiSkill's flattening is wrong: refuse rather than mis-decode
        raise EpisodeError(f"state layout of {u.spec.id if u.spec else type(u).__name__} covers {start} values, "
                           f"but get_state() has {total}")
    return layout


def flat_env_state(env: gym.Env) -> np.ndarray:
    """[E] float32 ``env.unwrapped.get_state()`` of a one-env env (controller state included)."""
    return _base(env).get_state()[0].detach().cpu().numpy().astype(np.float32)


def set_flat_env_state(env: gym.Env, state: np.ndarray, layout: dict[str, slice] | None = None):
    """Restore a flat state from :func:`flat_env_state`: actors, articulations *and* controller targets."""
    u = _base(env)
    layout = state_layout(env) if layout is None else layout
    state = np.asarray(state, dtype=np.float32).reshape(-1)
    expected = max(s.stop for s in layout.values())
    if state.shape[0] != expected:
        raise EpisodeError(f"env state has {state.shape[0]} values; this env's state has {expected}")
    u.set_state(torch.as_tensor(state, device=u.device)[None])  # TaskEnv restores controller targets too


def object_positions(env: gym.Env, state: np.ndarray | None = None,
                     layout: dict[str, slice] | None = None) -> dict[str, np.ndarray]:
    """Task object name -> [3] world position (root link for articulations): now, or decoded from a flat state."""
    u = _base(env)
    if state is None:
        return {n: e.pose.p[0].detach().cpu().numpy().astype(np.float64) for n, e in u.objects.items()}
    layout = state_layout(env) if layout is None else layout
    state = np.asarray(state).reshape(-1)
    out = {}
    for name, entity in u.objects.items():
        key = next((k for k in (f"actors/{entity.name}", f"articulations/{entity.name}") if k in layout), None)
        if key is None:  # static (fixed) actors are not part of the state: they never move
            out[name] = entity.pose.p[0].detach().cpu().numpy().astype(np.float64)
        else:
            out[name] = state[layout[key]][:3].astype(np.float64)
    return out


def robot_state(env: gym.Env) -> np.ndarray:
    """[S] float32 robot joint positions then velocities (``observation.state``)."""
    _base(env)
    return observation.robot_state(env)[0].detach().cpu().numpy().astype(np.float32)


def environment_state(env: gym.Env) -> np.ndarray:
    """[K] float32 the world as a learner observes it (``observation.environment_state``)."""
    _base(env)
    return observation.environment_state(env)[0].detach().cpu().numpy().astype(np.float32)


def max_episode_steps(env: gym.Env) -> int:
    """The time limit of a ``gym.make`` env (its TimeLimit wrapper), else the task's ``max_episode_steps``."""
    from gendex_envs.wrappers import time_limit

    steps = time_limit(env)
    return int(steps if steps is not None else env.unwrapped.task_spec.max_episode_steps)


def env_info(env: gym.Env) -> dict:
    """``{env_id, env_kwargs, max_episode_steps}`` for :class:`~gendex.data.trajectory_h5.TrajectoryWriter`.

    ``env_kwargs`` are the ``gym.make`` keyword arguments, without ``task`` (the registry supplies the version folder
    from the env id, and a machine's absolute path would make the file unportable)."""
    spec = env.spec if env.spec is not None else env.unwrapped.spec
    if spec is None:
        raise EpisodeError("env was not made with gym.make: no env id to record")
    kwargs = {k: v for k, v in (spec.kwargs or {}).items() if k != "task"}
    return dict(env_id=spec.id, env_kwargs=kwargs, max_episode_steps=max_episode_steps(env))


class EpisodeRecorder:
    """Record an episode step by step (closed-loop solvers): as the hooks of one run of the episode loop
    (:meth:`hooks`), or by hand: ``begin(seed)``, ``step(action)``..., then ``episode()``."""

    def __init__(self, env: gym.Env):
        self.env = env
        self._u = _base(env)

    def hooks(self, seed: int, see: Callable[[Any], None] | None = None) -> Hooks:
        """Hooks of :func:`gendex.episode_loop.run_episode` that record its episode from ``env.reset(seed=seed)``:
        every action is stepped as float32 ``[A]`` and recorded; ``see`` sees every observation."""
        def on_reset(obs, info) -> None:
            self.start(seed)
            if see is not None:
                see(obs)

        def on_step(step: Step) -> None:
            self.record(step.action, step.reward, step.info)
            if see is not None:
                see(step.obs)

        return Hooks(prepare=self.as_action, on_reset=on_reset, on_step=on_step)

    def begin(self, seed: int):
        """Reset with ``seed`` and record the initial state; returns the reset's (obs, info)."""
        out = self.env.reset(seed=int(seed))
        self.start(seed)
        return out

    def start(self, seed: int) -> None:
        """Record the initial state of an episode the env was just reset into with ``seed``."""
        self.seed = int(seed)
        self._states, self._env_states = [robot_state(self.env)], [flat_env_state(self.env)]
        self._world = [environment_state(self.env)]
        self._actions, self._rewards, self._success, self._fail = [], [], [], []
        drawn = getattr(self._u, "appearance", None)
        self._appearance = dict(drawn[0]) if drawn else {}

    def as_action(self, action) -> np.ndarray:
        """``action`` as what is stepped and recorded: float32 ``[A]``."""
        return np.asarray(action, dtype=np.float32).reshape(self.env.action_space.shape[-1:])

    def step(self, action):
        """Step ``action`` and record it; returns ``env.step``'s result."""
        action = self.as_action(action)
        out = self.env.step(action)
        self.record(action, out[1], out[4])
        return out

    def record(self, action: np.ndarray, reward, step_info: dict) -> None:
        """Record a step the env just took with ``action`` (from :meth:`as_action`)."""
        self._actions.append(action.copy())
        self._rewards.append(_scalar(reward))
        self._success.append(bool(_scalar(step_info["success"])))
        self._fail.append(bool(_scalar(step_info.get("fail", False))))
        self._states.append(robot_state(self.env))
        self._env_states.append(flat_env_state(self.env))
        self._world.append(environment_state(self.env))

    @property
    def steps(self) -> int:
        return len(self._actions)

    def episode(self, info: dict | None = None) -> Episode:
        u = self._u
        if not self._actions:
            raise EpisodeError("an episode needs at least one action")
        spec = self.env.spec if self.env.spec is not None else u.spec
        return Episode(
            task_id=spec.id if spec is not None else u.task_spec.name, instruction=u.task_spec.instruction,
            seed=self.seed, control_mode=u.control_mode, control_joint=u.control_joint, fps=int(u.control_freq),
            state=np.stack(self._states), action=np.stack(self._actions),
            reward=np.asarray(self._rewards, dtype=np.float32), success=np.asarray(self._success, dtype=bool),
            fail=np.asarray(self._fail, dtype=bool), env_states=np.stack(self._env_states),
            environment_state=np.stack(self._world),
            environment_state_names=tuple(observation.environment_state_names(self.env)),
            reset_kwargs={"seed": self.seed}, info=dict(info or {}), appearance=self._appearance)


def record_rollout(env: gym.Env, seed: int, actions: np.ndarray | Sequence, *, info: dict | None = None) -> Episode:
    """Reset ``env`` with ``seed``, step every action and return the :class:`Episode` (env states included).

    All actions are stepped, also after success or failure (ManiSkill envs do not auto-reset). ``env`` is a
    one-env GenDex env, with the Gymnasium (numpy) API or the batched one."""
    actions = np.asarray(actions, dtype=np.float32)
    shape = env.action_space.shape[-1:]
    if actions.ndim != 2 or actions.shape[1:] != shape or len(actions) == 0:
        raise EpisodeError(f"actions must be [T, {shape[0]}] with T >= 1, got {list(actions.shape)}")
    recorder = EpisodeRecorder(env)
    recorder.begin(seed)
    for a in actions:
        recorder.step(a)
    return recorder.episode(info)


def replay_rollout(env: gym.Env, actions: np.ndarray, env_states: np.ndarray, success: np.ndarray, *,
                   reset_kwargs: dict, episode_id: int = 0, use_env_states: bool = False,
                   init_tol: float = 1e-4) -> ReplayResult:
    """Reset ``env`` with ``reset_kwargs``, check the reset state against ``env_states[0]`` (:class:`ReplayError`
    beyond ``init_tol``), step ``actions`` and compare with the recording (``env_states`` [T+1, E], ``success`` [T]).

    Object positions are compared after the last action: the replayed ones read from the entities, the recorded ones
    decoded from ``env_states[-1]`` (no state is set to read them). ``use_env_states`` restores the recorded state
    after each step (ManiSkill's ``--use-env-states``); that resets PhysX's contact caches, which the state does not
    hold, so such replays differ slightly even from themselves, whereas a plain replay on the same build is exact."""
    actions = np.asarray(actions, dtype=np.float32)
    if actions.ndim != 2 or actions.shape[1] != env.action_space.shape[-1]:
        raise ReplayError(f"episode {episode_id} has actions of {actions.shape[-1]} values ({list(actions.shape)}); "
                          f"the env takes {env.action_space.shape[-1]}")
    layout = state_layout(env)
    env.reset(**reset_kwargs)
    s0 = flat_env_state(env)
    if s0.shape != env_states.shape[1:]:
        raise ReplayError(f"episode {episode_id} has env states of {env_states.shape[1]} values; the env's have "
                          f"{s0.shape[0]}")
    err0 = np.abs(s0 - env_states[0])
    if err0.max() > init_tol:
        i = int(err0.argmax())
        part = next(k for k, sl in layout.items() if sl.start <= i < sl.stop)
        raise ReplayError(f"episode {episode_id}: the reset state differs from the recording by {err0.max():.3g} "
                          f"(at {part}); the env or its assets changed since recording")
    max_err, replayed_success = 0.0, []
    replayed_pos: dict[str, np.ndarray] = {}
    for t, a in enumerate(actions):
        _, _, _, _, info = env.step(a)
        replayed_success.append(bool(_scalar(info["success"])))
        max_err = max(max_err, float(np.abs(flat_env_state(env) - env_states[t + 1]).max()))
        if t == len(actions) - 1:
            replayed_pos = object_positions(env)
        if use_env_states:
            set_flat_env_state(env, env_states[t + 1], layout)
    recorded_pos = object_positions(env, env_states[-1], layout)
    errs = {n: float(np.linalg.norm(replayed_pos[n] - recorded_pos[n])) for n in recorded_pos}
    success = np.asarray(success, dtype=bool)
    return ReplayResult(episode_id=episode_id, steps=len(actions), success_recorded=bool(success[-1]),
                        success_replayed=replayed_success[-1], max_object_pos_err_m=max(errs.values(), default=0.0),
                        max_env_state_err=max_err, object_pos_err_by_name=errs,
                        success_steps_differing=int((success != np.asarray(replayed_success)).sum()))
