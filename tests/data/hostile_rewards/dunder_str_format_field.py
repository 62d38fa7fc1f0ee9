# expect: contains `__`
# class: dunder
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: str.format reaching `{0.__class__}`."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    s = "{0.__class__}".format(env)
    return torch.zeros(env.num_envs, device=env.device)
