# expect: attribute `.__subclasses__`
# class: dunder
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: the classic ().__class__.__mro__ escape."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    x = ().__class__.__mro__[1].__subclasses__()
    return torch.zeros(env.num_envs, device=env.device)
