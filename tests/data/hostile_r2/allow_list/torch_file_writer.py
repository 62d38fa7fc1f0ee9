# expect: `torch.PyTorchFileWriter` is not allowed
# runtime: may not use torch.PyTorchFileWriter
"""Hostile: torch's public re-export of its archive writer creates a file with no audit event."""
import math

import torch
import torch.nn.functional as F

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    w = torch.PyTorchFileWriter(MARKER)
    w.write_end_of_file()
    return rt.fraction(torch.zeros(env.num_envs, device=env.device)) * math.pi * F.relu(torch.zeros(1))
