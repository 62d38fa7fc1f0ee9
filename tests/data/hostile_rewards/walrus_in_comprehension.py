# expect: (NamedExpr)
# class: syntax
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a walrus in a comprehension rebinds a name of the enclosing function."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    xs = [(dir := x) for x in obs]
    return torch.zeros(env.num_envs, device=env.device)
