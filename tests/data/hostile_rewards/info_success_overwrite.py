# expect: which this function did not create
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: overwriting info['success'] in compute_dense_reward."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    info["success"] = torch.ones_like(info["success"])
    return torch.zeros(env.num_envs, device=env.device)
