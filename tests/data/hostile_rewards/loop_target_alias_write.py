# expect: which this function did not create
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a loop variable holding the env's tensors."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    for t in [env.palm_pose.p, env.tip_positions]:
        t[:] = 0
    return torch.zeros(env.num_envs, device=env.device)
