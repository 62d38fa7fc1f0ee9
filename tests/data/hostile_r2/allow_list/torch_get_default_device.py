# expect: `torch.get_default_device` is not allowed
# runtime: may not use torch.get_default_device
"""Hostile: a function outside the allow-list, however harmless."""
import math

import torch
import torch.nn.functional as F

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    d = torch.get_default_device()
    return rt.fraction(torch.zeros(env.num_envs, device=env.device)) * math.pi * F.relu(torch.zeros(1))
