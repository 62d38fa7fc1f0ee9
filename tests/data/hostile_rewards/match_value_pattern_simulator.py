# expect: (Match)
# class: match
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a value pattern looks up the env's scene."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    match obs:
        case env.scene:
            pass
    return torch.zeros(env.num_envs, device=env.device)
