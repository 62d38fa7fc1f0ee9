# expect: is too large
# class: resources
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: an enormous integer literal."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    x = 123456789012345678901234567890
    return torch.zeros(env.num_envs, device=env.device)
