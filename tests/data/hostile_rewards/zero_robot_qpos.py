# expect: attribute `.zero_`
# class: mutation
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: zero_ on the joint positions."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    env.agent.robot.get_qpos().zero_()
    return torch.zeros(env.num_envs, device=env.device)
