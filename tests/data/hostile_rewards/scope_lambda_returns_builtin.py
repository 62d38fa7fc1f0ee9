# expect: the builtin `type` is not allowed in reward code (in `lambda`)
# class: scope
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a lambda smuggles the builtin `type` out as a value."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    f = lambda: type
    k = f()(env)
    return torch.zeros(env.num_envs, device=env.device)
