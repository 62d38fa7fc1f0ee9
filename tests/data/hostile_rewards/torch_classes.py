# expect: attribute `.classes`
# class: modules
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: torch.classes."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    c = torch.classes
    return torch.zeros(env.num_envs, device=env.device)
