# expect: `rt.torch` is not allowed: reward code may use only
# class: modules
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a module reached through the helpers' own imports."""

import torch

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    g = rt.torch.random.fork_rng
    return torch.zeros(env.num_envs, device=env.device)
