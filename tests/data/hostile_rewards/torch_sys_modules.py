# expect: attribute `.sys`
# class: modules
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: sys.modules through torch."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    m = torch.sys.modules["os"]
    return torch.zeros(env.num_envs, device=env.device)
