# expect: attribute `.ops`
# class: modules
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: torch.ops reaches registered operators."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    op = torch.ops.aten.add
    return torch.zeros(env.num_envs, device=env.device)
