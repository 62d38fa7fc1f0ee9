# expect: utf-7` is not allowed; only UTF-8 is allowed
# -*- coding: utf-7 -*-
"""Hostile: under UTF-7 `+AAo-` is a newline, so the last comment is code to the importer, a comment to the checker."""
import torch


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)

# note +AAo-g = getattr.__globals__+AAo-g["_untrusted"] = ()+AAo-g["builtins"].open(MARKER, "w").write("pwned")
