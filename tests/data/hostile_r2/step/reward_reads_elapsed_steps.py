"""A reward that waits out the probe by reading info["elapsed_steps"]: 1 while it can see the step count and it is
20 or less, NaN after; 0 when it cannot see it."""

import math

import torch

REWARD_MAX = 1.0


def evaluate(env):
    apple = env.obj_pose("apple").p
    return {"fail": apple[:, 2] < env.table_height - 0.05, "apple_height": env.obj_height("apple")}


def compute_dense_reward(env, obs, action, info):
    zero = torch.zeros(env.num_envs, device=env.device)
    if "elapsed_steps" in info:
        late = info["elapsed_steps"] > 20
        return torch.where(late, torch.full_like(zero, math.nan), zero + 1.0)
    return zero
