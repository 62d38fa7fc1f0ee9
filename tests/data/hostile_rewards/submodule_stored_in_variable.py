# expect: `F.torch` is not allowed: reward code may use only
# class: modules
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a module reached through another module's attribute, stored in a variable."""

import torch

import torch.nn.functional as F


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    t = F.torch
    t.random.fork_rng()
    return torch.zeros(env.num_envs, device=env.device)
