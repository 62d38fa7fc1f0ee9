# expect: may only be used as `torch.<name>`
# class: modules
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: the torch module stored in a variable."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    t = torch
    t.load("x")
    return torch.zeros(env.num_envs, device=env.device)
