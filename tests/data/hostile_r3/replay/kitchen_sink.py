"""Honest reward module (passes the static check) using what a recording could get wrong: a view changed through
an in-place update of its base, iteration over a tensor, the keys and entries of ``info``, branches on data,
reward_terms, the view's static members, tensor metadata read as Python values."""

import math

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 10.0


def evaluate(env):
    p = env.obj_pose("apple").p
    return {"fail": p[:, 2] < -10.0, "height": p[:, 2] * 1.0}


def compute_dense_reward(env, obs, action, info):
    p = env.obj_pose("apple").p.clone()
    z = p[:, 0]  # a view of p
    p += 0.5  # moves z too
    total = torch.zeros(env.num_envs, device=env.device)
    for row in p:  # iteration over a tensor
        total = total + row.sum() * 0.1
    for key in sorted(info.keys()):
        total = total + info[key].float() * 0.01
    if bool((z > 0.55).any()):  # a branch on data
        total = total * 2.0
    else:
        total = total - 0.25
    big = max(float((z > 100.0).any()), 0.5)  # a Python float from data
    total = total + rt.tips_reach(env.tip_positions, env.obj_pose("apple").p) + math.sqrt(big)
    n = len(env.object_names) + env.num_envs + p.shape[1] + getattr(p, "ndim")  # noqa: B009 (getattr as reward code writes it)
    return total + z * n + rt.lift(env.obj_height("apple"), 0.1)
