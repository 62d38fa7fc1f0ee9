# expect: attribute `.load`
# class: modules
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: torch.load unpickles a file."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    w = torch.load("w.pt")
    return torch.zeros(env.num_envs, device=env.device)
