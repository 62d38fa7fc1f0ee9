# expect: `.update()` changes
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: info.update faking success."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    info.update({"success": torch.ones(env.num_envs, dtype=torch.bool)})
    return torch.zeros(env.num_envs, device=env.device)
