# expect: `torch.empty_like` is not allowed
# runtime: may not use torch.empty_like
"""Hostile: empty_like hands out uninitialised memory."""
import math

import torch
import torch.nn.functional as F

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    leak = torch.empty_like(env.tip_positions)
    return rt.fraction(torch.zeros(env.num_envs, device=env.device)) * math.pi * F.relu(torch.zeros(1))
