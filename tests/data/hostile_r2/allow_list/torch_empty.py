# expect: `torch.empty` is not allowed
# runtime: may not use torch.empty
"""Hostile: torch.empty hands out uninitialised memory (other tensors' old contents)."""
import math

import torch
import torch.nn.functional as F

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    leak = torch.empty(env.num_envs, 4096)
    return rt.fraction(torch.zeros(env.num_envs, device=env.device)) * math.pi * F.relu(torch.zeros(1))
