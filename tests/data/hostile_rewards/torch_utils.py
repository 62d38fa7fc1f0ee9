# expect: attribute `.utils`
# class: modules
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: torch.utils.cpp_extension builds native code."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    f = torch.utils.cpp_extension.load_inline
    return torch.zeros(env.num_envs, device=env.device)
