# expect: attribute `.copy_`
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: copy_ into the fingertip tensor."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    env.tip_positions.copy_(torch.zeros(env.num_envs, 5, 3))
    return torch.zeros(env.num_envs, device=env.device)
