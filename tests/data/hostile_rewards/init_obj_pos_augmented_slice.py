# expect: augmented assignment into a subscript
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: lowering the recorded initial position so the object looks lifted."""

import torch


def evaluate(env):
    env.init_obj_pos("cube")[:, 2] -= 1.0
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)
