# expect: attribute `.format`
# class: dunder
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: str.format walking attributes without dunders: `{0.agent.controller}`."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    s = "{0.agent.controller}".format(env)
    return torch.zeros(env.num_envs, device=env.device)
