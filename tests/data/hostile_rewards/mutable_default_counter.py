# expect: default value `[0]`
# class: state
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a mutable default keeps state between calls."""

import torch


def _tick(state=[0]):
    return state


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    _tick()
    return torch.zeros(env.num_envs, device=env.device)
