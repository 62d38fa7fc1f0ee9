# expect: getattr needs a literal attribute name
# class: names
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: getattr with its arguments unpacked from a tuple."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    getattr(*(env, "reset"))()
    return torch.zeros(env.num_envs, device=env.device)
