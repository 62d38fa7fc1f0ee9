# expect: `.from_file` in `torch.UntypedStorage.from_file` is not allowed
# runtime: may not use torch.UntypedStorage
"""Hostile: a storage mapped from a file creates and truncates it."""
import math

import torch
import torch.nn.functional as F

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    s = torch.UntypedStorage.from_file(MARKER, True, 8)
    return rt.fraction(torch.zeros(env.num_envs, device=env.device)) * math.pi * F.relu(torch.zeros(1))
