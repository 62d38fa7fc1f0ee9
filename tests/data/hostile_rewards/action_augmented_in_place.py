# expect: may change `action` in place
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: `action += ...` changes the policy's action tensor in place."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    action += 1.0
    return torch.zeros(env.num_envs, device=env.device)
