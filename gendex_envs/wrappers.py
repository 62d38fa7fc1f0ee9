"""``GymApi``: the outermost wrapper of every GenDex env made with ``gym.make``.

``gym.make("GenDex/<Name>-v<N>")`` builds the bare :class:`~gendex_envs.task_env.TaskEnv` (ManiSkill's torch-batched
env), then Gymnasium applies its own ``TimeLimit`` (the registered ``max_episode_steps``, or the one passed to
``gym.make``), then this wrapper. It gives one of two APIs:

* **numpy** (default for one CPU env): the plain Gymnasium API — numpy observations without a batch dimension,
  Python scalars for reward, terminated and truncated, single-env spaces.
* **batched** (``num_envs > 1``, the GPU backend, or ``gym_api=False``): torch tensors ``[num_envs, ...]`` on the
  env's device, as ManiSkill returns them.

Truncation is per sub-scene in both: an episode is truncated when *its* step count (``elapsed_steps``, which
partial resets restart) reaches the time limit, or a stage env's horizon. Gymnasium's ``TimeLimit`` counts calls
of the whole env and answers a Python ``True`` for a batch, so its flag is replaced; its limit is kept.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import torch
from mani_skill.utils import common

from gendex_envs.errors import GenDexError


class GymApi(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """See the module docstring. ``env`` is what ``gym.make`` built below it (``TimeLimit`` over the TaskEnv)."""

    def __init__(self, env: gym.Env):
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.Wrapper.__init__(self, env)
        base = env.unwrapped
        self.max_episode_steps: int | None = time_limit(env)
        """Steps after which an episode is truncated (None: never, e.g. ``gym.make(..., max_episode_steps=-1)``)."""
        single = base.num_envs == 1 and not base.gpu_sim_enabled
        self.numpy = single if base.gym_api is None else bool(base.gym_api)
        """True: the plain numpy API of one env; False: the batched torch API."""
        if self.numpy and not single:
            raise GenDexError(f"gym_api=True needs one env on the CPU backend; this env has num_envs="
                              f"{base.num_envs} on {'the GPU' if base.gpu_sim_enabled else 'the CPU'} (drop gym_api "
                              "to get the batched torch API)")
        if self.numpy:
            self.observation_space = base.single_observation_space
            self.action_space = base.single_action_space

    def _truncated(self, truncated) -> torch.Tensor:
        base = self.env.unwrapped
        out = torch.zeros(base.num_envs, dtype=torch.bool, device=base.device)
        if isinstance(truncated, torch.Tensor):  # TaskEnv's own (a stage env's horizon)
            out |= truncated.to(torch.bool)
        if self.max_episode_steps is not None:
            out |= base.elapsed_steps >= self.max_episode_steps
        return out

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        if not self.numpy:
            return obs, reward, terminated, self._truncated(truncated), info
        base = self.env.unwrapped  # one env: the flag as a Python bool, without building a batch of one
        ended = isinstance(truncated, torch.Tensor) and bool(truncated.any())
        if self.max_episode_steps is not None:
            ended = ended or bool((base.elapsed_steps >= self.max_episode_steps).any())
        return (unbatched_numpy(obs), float(unbatched_numpy(reward)), bool(unbatched_numpy(terminated)), ended,
                unbatched_numpy(info))

    def reset(self, *, seed=None, options=None):
        obs, info = self.env.reset(seed=seed, options=options)
        if not self.numpy:
            return obs, info
        return unbatched_numpy(obs), unbatched_numpy(info)

    def render(self):
        frames = self.env.render()
        if self.numpy and self.render_mode in ("rgb_array", "sensors", "all"):
            return common.unbatch(common.to_numpy(frames))
        return frames


def unbatched_numpy(value):
    """``common.unbatch(common.to_numpy(value))`` in one pass (the same values and types): tensors become numpy
    arrays, a leading batch dimension of one is dropped and a one-element array becomes a Python scalar."""
    if isinstance(value, dict):
        return {k: unbatched_numpy(v) for k, v in value.items()}
    if isinstance(value, torch.Tensor):
        value = value.cpu().numpy()
    elif isinstance(value, bool | str | float | int):
        return value
    elif not isinstance(value, np.ndarray):
        value = np.array(value)
    if value.shape == (1,):
        return value.item()
    if value.ndim > 0 and value.shape[0] == 1:
        return value.squeeze(0)
    return value


def time_limit(env: gym.Env) -> int | None:
    """The ``max_episode_steps`` of the first Gymnasium ``TimeLimit`` in ``env``'s wrapper chain, else None."""
    while isinstance(env, gym.Wrapper):
        if isinstance(env, gym.wrappers.TimeLimit):
            return env._max_episode_steps  # noqa: SLF001  (Gymnasium keeps the limit only there)
        env = env.env
    return None
