# expect: cp1252` is not allowed; only UTF-8 is allowed
#!/usr/bin/env python  coding=cp1252
"""Hostile: a `coding=` declaration after a shebang, on line 2."""
import torch


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)

