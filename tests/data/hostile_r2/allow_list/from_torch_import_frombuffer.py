# expect: from torch import frombuffer
# runtime: may not use torch.frombuffer
"""Hostile: the from-import form."""
import math

import torch
import torch.nn.functional as F
from torch import frombuffer

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    n = 0
    return rt.fraction(torch.zeros(env.num_envs, device=env.device)) * math.pi * F.relu(torch.zeros(1))
