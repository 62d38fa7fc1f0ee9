# expect: which this function did not create
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a local function named `list` returns the env's tensor itself."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    def list(t):
        return t

    x = list(env.palm_pose.p)
    x[0] = 0.0
    return torch.zeros(env.num_envs, device=env.device)
