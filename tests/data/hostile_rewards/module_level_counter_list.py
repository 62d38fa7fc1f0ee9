# expect: is not a constant
# class: state
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a module-level list used as a step counter."""

import torch


_CALLS = []


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    _CALLS.append(1)
    return torch.zeros(env.num_envs, device=env.device)
