# expect: `compile` is not allowed
# class: names
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: compile of a string."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    code = compile("1", "f", "eval")
    return torch.zeros(env.num_envs, device=env.device)
