# expect: attribute `.add_`
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: add_ on the tensor obj_pose returns."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    env.obj_pose("cube").p.add_(1.0)
    return torch.zeros(env.num_envs, device=env.device)
