# expect: contains `__`
# class: dunder
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a dunder assembled from pieces of strings."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    name = "__cla" + "ss__"
    return torch.zeros(env.num_envs, device=env.device)
