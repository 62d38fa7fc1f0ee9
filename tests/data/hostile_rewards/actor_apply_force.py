# expect: attribute `.add_force_torque`
# class: simulator
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: pushing an object with a force."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    env.obj("cube").add_force_torque(torch.ones(3), torch.zeros(3))
    return torch.zeros(env.num_envs, device=env.device)
