"""Environments PPO trains on: one stage (or the whole task) of a GenDex task, as SB3 vector envs.

Training episodes differ from evaluation ones in one way: reaching the stage's goal does not end the episode, so
the agent keeps earning the success reward until the horizon (ending it would make success worth less than
hovering next to it); a failure (``evaluate()['fail']``, e.g. the object fell off the table) does end it.
``info['is_success']`` (success at any step) feeds SB3's ``rollout/success_rate`` curve.
"""

from __future__ import annotations

from collections.abc import Callable

import gymnasium as gym

from gendex.solve.policy import WHOLE_TASK
from gendex_envs.start_states import StartStates
from gendex_envs.task_version import TaskVersion

TASK_STAGE = WHOLE_TASK
"""Name of the pseudo-stage that is the whole task (the ablation's "no sub-goals" variant)."""


class StageEpisodes(gym.Wrapper):
    """Numpy stage env for PPO: episodes end on failure or at the horizon, not on success (see the module doc)."""

    def reset(self, **kwargs):
        self._success = False
        return self.env.reset(**kwargs)

    def step(self, action):
        obs, reward, _, truncated, info = self.env.step(action)
        self._success |= bool(info["success"])
        terminated = bool(info.get("fail", False))
        if terminated or truncated:
            info["is_success"] = self._success
        return obs, float(reward), terminated, bool(truncated), info


def make_stage_env(version: TaskVersion, stage: str | None, *, control_joint: str | None = None,
                   start_states: StartStates | None = None, training: bool = True,
                   max_episode_steps: int | None = None) -> gym.Env:
    """One numpy env of ``stage`` (None: the whole task) with normalized joint-delta actions and flat state obs."""
    from mani_skill.utils.wrappers.gymnasium import CPUGymWrapper

    from gendex_envs.registry import make_env

    env = make_env(version, stage=None if stage in (None, TASK_STAGE) else stage,
                   start_states=start_states, control_joint=control_joint, control_mode="pd_joint_delta_pos",
                   obs_mode="state", reward_mode="normalized_dense", gym_api=False,
                   max_episode_steps=max_episode_steps)
    env = CPUGymWrapper(env, ignore_terminations=training)
    return StageEpisodes(env) if training else env


def env_factory(version: TaskVersion, stage: str | None, **kwargs) -> Callable[[], gym.Env]:
    """A picklable constructor for one worker process (one torch thread each: two cores, two workers)."""

    def make() -> gym.Env:
        import torch
        from stable_baselines3.common.monitor import Monitor

        torch.set_num_threads(1)
        return Monitor(make_stage_env(version, stage, **kwargs), info_keywords=("is_success",))

    return make


def make_vec_env(version: TaskVersion, stage: str | None, n_envs: int, seed: int, **kwargs):
    """``n_envs`` stage envs: worker processes when ``n_envs`` > 1, else in this process."""
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    fns = [env_factory(version, stage, **kwargs) for _ in range(n_envs)]
    venv = SubprocVecEnv(fns) if n_envs > 1 else DummyVecEnv(fns)
    venv.seed(seed)
    return venv


class _FailOnlyTermination(gym.Wrapper):
    """Batched counterpart of :class:`StageEpisodes` for the GPU backend: only ``fail`` ends an episode."""

    def step(self, action):
        obs, reward, _, truncated, info = self.env.step(action)
        return obs, reward, info["fail"].clone(), truncated, info


def make_gpu_vec_env(version: TaskVersion, stage: str | None, n_envs: int, seed: int, *,
                     control_joint: str | None = None, start_states: StartStates | None = None):
    """``n_envs`` sub-scenes of one ManiSkill GPU-backend env as an SB3 VecEnv (needs CUDA)."""
    from mani_skill.vector.wrappers.sb3 import ManiSkillSB3VectorEnv

    from gendex_envs.registry import make_env

    env = make_env(version, num_envs=n_envs, sim_backend="physx_cuda", gym_api=False,
                   stage=None if stage in (None, TASK_STAGE) else stage, start_states=start_states,
                   control_joint=control_joint, control_mode="pd_joint_delta_pos", obs_mode="state",
                   reward_mode="normalized_dense")
    venv = ManiSkillSB3VectorEnv(_FailOnlyTermination(env))
    venv.seed(seed)
    return venv
