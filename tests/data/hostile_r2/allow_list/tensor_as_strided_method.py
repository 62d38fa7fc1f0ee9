# expect: attribute `.as_strided` in
# runtime: static only
"""Hostile: the method form of as_strided (tensor methods cannot be withheld in-process; the worker process is the wall behind the check)."""
import math

import torch
import torch.nn.functional as F

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    leak = env.tip_positions.as_strided((1 << 20,), (1,))
    return rt.fraction(torch.zeros(env.num_envs, device=env.device)) * math.pi * F.relu(torch.zeros(1))
