# expect: `torch.PyTorchFileReader` is not allowed
# runtime: may not use torch.PyTorchFileReader
"""Hostile: torch's public re-export of its archive reader opens any file with no audit event."""
import math

import torch
import torch.nn.functional as F

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    r = torch.PyTorchFileReader("/etc/hostname")
    n = len(r.get_all_records())
    return rt.fraction(torch.zeros(env.num_envs, device=env.device)) * math.pi * F.relu(torch.zeros(1))
