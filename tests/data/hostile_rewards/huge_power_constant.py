# expect: a power of a power
# class: resources
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: 10**10**10 never finishes."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    x = 10 ** 10 ** 10
    return torch.zeros(env.num_envs, device=env.device)
