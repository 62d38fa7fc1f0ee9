# expect: the builtin `object` is not allowed in reward code (in `evaluate`)
# class: scope
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a helper takes a parameter named `object`; evaluate then calls the builtin."""

import torch


def _helper(object):
    return object


def evaluate(env):
    o = object()
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)
