# expect: the builtin `type` is not allowed in reward code (in `compute_dense_reward`)
# class: scope
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: `type` is rebound inside a helper; the rebinding must not unlock the builtin in compute_dense_reward."""

import torch


def _helper(x):
    type = abs
    return type(x)


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    t = type(env)
    return torch.zeros(env.num_envs, device=env.device)
