# expect: attribute `.manual_seed`
# class: simulator
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: reseeding torch's global generator."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    torch.manual_seed(0)
    return torch.zeros(env.num_envs, device=env.device)
