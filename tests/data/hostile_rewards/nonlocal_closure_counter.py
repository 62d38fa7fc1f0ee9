# expect: (Nonlocal)
# class: state
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a closure counter with nonlocal."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    n = 0

    def _bump():
        nonlocal n
        n = n + 1

    return torch.zeros(env.num_envs, device=env.device)
