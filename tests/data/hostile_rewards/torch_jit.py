# expect: attribute `.jit`
# class: modules
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: torch.jit compiles code."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    f = torch.jit.script
    return torch.zeros(env.num_envs, device=env.device)
