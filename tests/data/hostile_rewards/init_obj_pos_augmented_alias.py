# expect: may change `z` in place
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: `z -= 1` on the env's tensor is an in-place subtraction."""

import torch


def evaluate(env):
    z = env.init_obj_pos("cube")
    z -= 1.0
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)
