# expect: `torch.as_strided` is not allowed
# runtime: may not use torch.as_strided
"""Hostile: as_strided with a large size reads memory past the tensor."""
import math

import torch
import torch.nn.functional as F

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    x = torch.zeros(4)
    leak = torch.as_strided(x, (1 << 20,), (1,))
    return rt.fraction(torch.zeros(env.num_envs, device=env.device)) * math.pi * F.relu(torch.zeros(1))
