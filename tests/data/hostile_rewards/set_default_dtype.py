# expect: attribute `.set_default_dtype`
# class: simulator
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: changing torch's global default."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    torch.set_default_dtype(torch.float64)
    return torch.zeros(env.num_envs, device=env.device)
