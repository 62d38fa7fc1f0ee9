# expect: attribute `.requires_grad_`
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: requires_grad_ on an env tensor."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    env.palm_pose.p.requires_grad_()
    return torch.zeros(env.num_envs, device=env.device)
