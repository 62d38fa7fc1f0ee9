# expect: repeats a sequence
# class: resources
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a billion-character string."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    s = "a" * 1000000000
    return torch.zeros(env.num_envs, device=env.device)
