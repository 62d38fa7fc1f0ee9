# expect: utf-16` is not allowed; only UTF-8 is allowed
# coding: utf-16
"""Hostile: a declaration of a non-ASCII-compatible encoding."""
import torch


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)

