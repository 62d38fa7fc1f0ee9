# expect: (Match)
# class: match
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a match class pattern reads `controller` off the agent without an Attribute node."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    match env.agent:
        case object(controller=ctrl):
            ctrl.reset()
    return torch.zeros(env.num_envs, device=env.device)
