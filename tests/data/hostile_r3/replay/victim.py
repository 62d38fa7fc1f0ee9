"""Honest reward module (passes the static check): the reward follows the apple's x coordinate."""

import torch


def evaluate(env):
    return {"fail": env.obj_pose("apple").p[:, 2] < -10.0}


def compute_dense_reward(env, obs, action, info):
    return torch.tanh(env.obj_pose("apple").p[:, 0] * 10.0)
