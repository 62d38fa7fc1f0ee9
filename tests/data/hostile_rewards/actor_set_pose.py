# expect: attribute `.set_pose`
# class: simulator
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: teleporting the target object."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    env.obj("cube").set_pose(env.palm_pose)
    return torch.zeros(env.num_envs, device=env.device)
