# expect: `globals` is not allowed
# class: names
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: writing the module globals."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    globals()["REWARD_MAX"] = 1e9
    return torch.zeros(env.num_envs, device=env.device)
