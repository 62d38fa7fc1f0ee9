"""Shared fixtures. Sim tests run ManiSkill on the CPU (physx_cpu, num_envs=1)."""

from __future__ import annotations

import logging

import gymnasium as gym
import pytest

import gendex_envs  # noqa: F401  (registers the GenDex tasks)

logging.getLogger("gymnasium_robotics").setLevel(logging.ERROR)


@pytest.fixture
def make_env():
    """Factory for GenDex envs that closes every env it made when the test ends."""
    made = []

    def _make(env_id: str, **kwargs):
        env = gym.make(env_id, **kwargs)
        made.append(env)
        return env

    yield _make
    for env in made:
        env.close()
