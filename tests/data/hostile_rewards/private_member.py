# expect: attribute `._elapsed_steps`
# class: simulator
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: reading a private counter."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    n = env._elapsed_steps
    return torch.zeros(env.num_envs, device=env.device)
