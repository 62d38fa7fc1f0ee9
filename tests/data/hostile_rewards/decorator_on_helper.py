# expect: decorator on `_helper`
# class: syntax
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: decorators run at import time."""

import torch


@torch.no_grad()
def _helper(x):
    return x


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)
