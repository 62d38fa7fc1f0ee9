# expect: (Yield)
# class: syntax
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a generator helper."""

import torch


def _helper(x):
    yield x


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)
