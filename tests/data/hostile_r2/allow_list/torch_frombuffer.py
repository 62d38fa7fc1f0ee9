# expect: `torch.frombuffer` is not allowed
# runtime: may not use torch.frombuffer
"""Hostile: a tensor over an immutable bytes constant: writing into it changes the interpreter's object."""
import math

import torch
import torch.nn.functional as F

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    t = torch.frombuffer(b"GENDEX_INTERNED_CONSTANT", dtype=torch.uint8)
    t[0] = 88
    return rt.fraction(torch.zeros(env.num_envs, device=env.device)) * math.pi * F.relu(torch.zeros(1))
