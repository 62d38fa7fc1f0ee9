# expect: attribute `.index_put_`
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: index_put_ on an env tensor."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    env.palm_pose.p.index_put_((torch.tensor([0]),), torch.zeros(3))
    return torch.zeros(env.num_envs, device=env.device)
