# expect: imports belong at the top
# class: modules
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: an import inside a function."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    import math
    return torch.zeros(env.num_envs, device=env.device)
