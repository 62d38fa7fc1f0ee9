# expect: attribute `.controller`
# class: simulator
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: reaching the arm controller."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    targets = env.agent.controller.get_state()
    return torch.zeros(env.num_envs, device=env.device)
