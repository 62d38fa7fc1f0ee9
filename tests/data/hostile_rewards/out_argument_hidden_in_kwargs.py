# expect: in a call is not allowed
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: out= hidden in a ** dict."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    p = env.palm_pose.p
    torch.add(p, 1.0, **{"out": p})
    return torch.zeros(env.num_envs, device=env.device)
