# expect: (Try)
# class: syntax
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: try/except hiding a failing call."""

import torch


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    try:
        env.agent.robot.get_qpos()
    except Exception:
        pass
    return torch.zeros(env.num_envs, device=env.device)
