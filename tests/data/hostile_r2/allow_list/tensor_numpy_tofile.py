# expect: `.numpy` in
# runtime: may not import 'numpy
"""Hostile: a tensor's numpy array writes a file from C."""
import math

import torch
import torch.nn.functional as F

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    env.tip_positions.numpy().tofile(MARKER)
    return rt.fraction(torch.zeros(env.num_envs, device=env.device)) * math.pi * F.relu(torch.zeros(1))
