# expect: attribute `.step`
# class: simulator
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: stepping the env from reward code."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    env.step(action)
    return torch.zeros(env.num_envs, device=env.device)
