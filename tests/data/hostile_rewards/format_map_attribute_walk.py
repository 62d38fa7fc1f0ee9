# expect: attribute `.format_map`
# class: dunder
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: str.format_map walking attributes."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    s = "{e.agent}".format_map({"e": env})
    return torch.zeros(env.num_envs, device=env.device)
