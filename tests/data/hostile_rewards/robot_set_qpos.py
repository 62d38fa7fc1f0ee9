# expect: attribute `.set_qpos`
# class: simulator
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: overwriting the robot's joints."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    env.agent.robot.set_qpos(action)
    return torch.zeros(env.num_envs, device=env.device)
