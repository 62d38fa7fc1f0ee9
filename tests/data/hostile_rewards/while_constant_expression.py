# expect: loops forever
# class: resources
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a condition without variables: `while 1 == 1`."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    while 1 == 1:
        x = 1
    return torch.zeros(env.num_envs, device=env.device)
