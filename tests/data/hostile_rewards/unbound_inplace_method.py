# expect: attribute `.add_`
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: torch.Tensor.add_ called unbound."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    torch.Tensor.add_(env.palm_pose.p, 1.0)
    return torch.zeros(env.num_envs, device=env.device)
