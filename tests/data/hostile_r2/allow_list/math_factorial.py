# expect: `math.factorial` is not allowed
# runtime: may not use math.factorial
"""Hostile: unbounded big-integer work."""
import math

import torch
import torch.nn.functional as F

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    n = math.factorial(10 ** 6)
    return rt.fraction(torch.zeros(env.num_envs, device=env.device)) * math.pi * F.relu(torch.zeros(1))
