# expect: the builtin `iter` is not allowed in reward code (in `_inner`)
# class: scope
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: `iter` is bound in a sibling function only, not in the enclosing one."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    def _inner(x):
        return iter(x)

    def _other(iter):
        return iter

    return torch.zeros(env.num_envs, device=env.device)
