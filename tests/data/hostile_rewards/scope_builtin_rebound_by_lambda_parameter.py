# expect: the builtin `id` is not allowed
# class: scope
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a lambda parameter named `id` does not bind `id` outside the lambda."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    f = lambda id: id
    n = id(env)
    return torch.zeros(env.num_envs, device=env.device)
