# expect: `torch.empty_strided` is not allowed
# runtime: may not use torch.empty_strided
"""Hostile: empty_strided hands out uninitialised memory."""
import math

import torch
import torch.nn.functional as F

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    leak = torch.empty_strided((4, 4), (1, 1))
    return rt.fraction(torch.zeros(env.num_envs, device=env.device)) * math.pi * F.relu(torch.zeros(1))
