# expect: attribute `.gi_frame`
# class: syntax
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a generator's frame reaching globals."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    g = (x for x in obs).gi_frame.f_back
    return torch.zeros(env.num_envs, device=env.device)
