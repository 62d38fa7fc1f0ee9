# expect: `getattr` may only be called directly
# class: names
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: getattr passed around as a value."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    g = getattr
    g(env, "reset")()
    return torch.zeros(env.num_envs, device=env.device)
