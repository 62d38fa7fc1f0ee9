# expect: `__builtins__` is not allowed
# class: dunder
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: reaching __builtins__ by name."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    b = __builtins__
    return torch.zeros(env.num_envs, device=env.device)
