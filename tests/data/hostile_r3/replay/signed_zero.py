"""Honest-looking reward module (passes the static check): the bearing of the table cell the apple lies in.

``float(torch.round(...))`` is -0.0 for a small negative coordinate and 0.0 for a small positive one; the two are
equal under ``==`` but ``math.atan2`` tells them apart (-pi and pi). A replay guard that compares with ``==`` takes
one for the other and replays the recorded bearing."""

import math

import torch

REWARD_MAX = 1.0


def evaluate(env):
    return {"fail": env.obj_pose("apple").p[:, 2] < -10.0}


def compute_dense_reward(env, obs, action, info):
    p = env.obj_pose("apple").p
    row = float(torch.round(p[0, 1] * 10.0))  # the apple's 10 cm row on the table
    col = float(torch.round(p[0, 0] * 10.0)) - 5.0  # its column, counted from the far edge
    bearing = math.atan2(row, col)  # where that cell lies, seen from the far edge
    return torch.full((env.num_envs,), (bearing + math.pi) / (2.0 * math.pi))
