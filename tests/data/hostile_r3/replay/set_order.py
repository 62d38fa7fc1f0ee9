"""Honest-looking reward module (passes the static check) with a plain bug: it walks its stages in ``set`` order.

A set of strings iterates in an order set by the process's string-hash seed. The confined worker runs with its own
random seed, the user's process with another, so the worker records (and the parent replays) a different sum
than the same module computes in process."""

import torch

REWARD_MAX = 2.0
STAGES = ("up", "aim", "grab", "reach", "settle", "release", "approach", "withdrawn")


def evaluate(env):
    return {"fail": env.obj_pose("apple").p[:, 2] < -10.0}


def compute_dense_reward(env, obs, action, info):
    x = env.obj_pose("apple").p[:, 0]
    reward = torch.zeros(env.num_envs)
    for rank, stage in enumerate(set(STAGES)):  # meant: enumerate(STAGES)
        reward = reward + (0.5 ** rank) * torch.tanh(x * len(stage))
    return reward
