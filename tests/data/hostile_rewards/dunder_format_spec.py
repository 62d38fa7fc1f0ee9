# expect: contains `__`
# class: dunder
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: an f-string format spec holding a dunder."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    s = f"{env:__class__}"
    return torch.zeros(env.num_envs, device=env.device)
