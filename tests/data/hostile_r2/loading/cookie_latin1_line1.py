# expect: `coding: latin-1` is not allowed  # -*- coding: latin-1 -*-
"""Hostile: the declaration on line 1 (this header carries it)."""
import torch


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)

