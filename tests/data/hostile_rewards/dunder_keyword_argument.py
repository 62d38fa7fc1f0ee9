# expect: `__class__` is not allowed in reward code
# class: dunder
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a keyword argument named like a dunder."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    z = torch.zeros(3, __class__=1)
    return torch.zeros(env.num_envs, device=env.device)
