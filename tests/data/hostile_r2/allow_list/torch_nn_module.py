# expect: `torch.nn.Module` is not allowed
# runtime: may not use torch.nn.Module
"""Hostile: torch.nn offers only its functional module to reward code."""
import math

import torch
import torch.nn.functional as F

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    m = torch.nn.Module()
    return rt.fraction(torch.zeros(env.num_envs, device=env.device)) * math.pi * F.relu(torch.zeros(1))
