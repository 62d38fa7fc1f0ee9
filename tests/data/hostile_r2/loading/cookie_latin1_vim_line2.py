# expect: latin-1` is not allowed; only UTF-8 is allowed
# vim: set fileencoding=latin-1 :
"""Hostile: a vim-style declaration of another encoding on line 2."""
import torch


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)

