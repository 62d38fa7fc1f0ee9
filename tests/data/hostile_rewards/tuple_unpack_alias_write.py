# expect: which this function did not create
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: tuple unpacking binds the env's tensor."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    a, b = env.palm_pose.p, 1
    a[0] = 1.0
    return torch.zeros(env.num_envs, device=env.device)
