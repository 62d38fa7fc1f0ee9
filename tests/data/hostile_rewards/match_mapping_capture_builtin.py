# expect: (Match)
# class: match
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a mapping pattern captures `**rest`, a sequence pattern binds `type` in one branch."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    match info:
        case {"success": s, **rest}:
            pass
        case [type, *_]:
            pass
    return torch.zeros(env.num_envs, device=env.device)
