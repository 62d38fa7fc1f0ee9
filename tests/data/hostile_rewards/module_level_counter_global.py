# expect: (Global)
# class: state
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a module-level int bumped with `global`."""

import torch


_N = 0


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    global _N
    _N = _N + 1
    return torch.zeros(env.num_envs, device=env.device)
