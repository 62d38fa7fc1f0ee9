# expect: `.setdefault()` changes
# class: state
# ruff: noqa (deliberately hostile code: it only has to fail the static check)
"""Hostile reward module: a counter kept in the helpers' module."""

import torch

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"success": env.obj_height("cube") > 0.1}


def compute_dense_reward(env, obs, action, info):
    rt.STATE.setdefault("n", 0)
    return torch.zeros(env.num_envs, device=env.device)
