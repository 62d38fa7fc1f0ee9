# expect: `F.dropout` is not allowed
# runtime: may not use torch.nn.functional.dropout
"""Hostile: dropout draws from the global generator."""
import math

import torch
import torch.nn.functional as F

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    x = F.dropout(env.tip_positions, 0.5)
    return rt.fraction(torch.zeros(env.num_envs, device=env.device)) * math.pi * F.relu(torch.zeros(1))
