# expect: the builtin `dir` is not allowed
# class: scope
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a comprehension variable named `dir` does not bind `dir` for the rest of the function."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    names = [dir for dir in obs]
    d = dir(env)
    return torch.zeros(env.num_envs, device=env.device)
