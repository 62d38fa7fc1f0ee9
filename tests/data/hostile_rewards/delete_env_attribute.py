# expect: (Delete)
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: deleting an attribute of the env."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    del env.goal_pos
    return torch.zeros(env.num_envs, device=env.device)
