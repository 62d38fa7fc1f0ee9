# expect: attribute `.fill_`
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: fill_ on the palm position."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    env.palm_pose.p.fill_(0)
    return torch.zeros(env.num_envs, device=env.device)
