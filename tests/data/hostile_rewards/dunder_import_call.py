# expect: `__import__` is not allowed
# class: dunder
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: __import__('os')."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    os = __import__("o" + "s")
    return torch.zeros(env.num_envs, device=env.device)
