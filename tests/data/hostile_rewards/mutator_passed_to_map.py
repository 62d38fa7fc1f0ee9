# expect: `.update()` changes `info`
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: info.update handed to map instead of called."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    done = list(map(info.update, [{"success": info["success"] | True}]))
    return torch.zeros(env.num_envs, device=env.device)
