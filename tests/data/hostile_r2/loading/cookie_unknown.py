# expect: no-such-codec` is not allowed
# coding: no-such-codec
"""Hostile: a declaration of an encoding that does not exist."""
import torch


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)

