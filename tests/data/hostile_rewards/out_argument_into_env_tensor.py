# expect: keyword `out=`
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: torch.add writing its result into the env's tensor."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    torch.add(env.palm_pose.p, 1.0, out=env.palm_pose.p)
    return torch.zeros(env.num_envs, device=env.device)
