# expect: changes an attribute
# class: state
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a counter stored on a function object."""

import torch


def _tick(x):
    return x


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    _tick.count = 1
    return torch.zeros(env.num_envs, device=env.device)
