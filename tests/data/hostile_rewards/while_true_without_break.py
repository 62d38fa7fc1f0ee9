# expect: loops forever
# class: resources
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: an endless loop."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    while True:
        x = 1
    return torch.zeros(env.num_envs, device=env.device)
