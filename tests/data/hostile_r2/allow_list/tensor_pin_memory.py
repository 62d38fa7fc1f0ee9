# expect: `.pin_memory` in
# runtime: static only
"""Hostile: pinning host memory reaches the device allocator."""
import math

import torch
import torch.nn.functional as F

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    x = env.tip_positions.pin_memory()
    return rt.fraction(torch.zeros(env.num_envs, device=env.device)) * math.pi * F.relu(torch.zeros(1))
