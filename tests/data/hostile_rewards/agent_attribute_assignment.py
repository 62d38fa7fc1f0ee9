# expect: changes an attribute
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: assigning an attribute on the agent."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    env.agent.robot = None
    return torch.zeros(env.num_envs, device=env.device)
