# expect: keyword `inplace=`
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: F.relu(..., inplace=True) on an env tensor."""

import torch

import torch.nn.functional as F


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    F.relu(env.palm_pose.p, inplace=True)
    return torch.zeros(env.num_envs, device=env.device)
