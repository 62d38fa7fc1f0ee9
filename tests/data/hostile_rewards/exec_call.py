# expect: `exec` is not allowed
# class: names
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: exec of a string."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    exec("import os")
    return torch.zeros(env.num_envs, device=env.device)
