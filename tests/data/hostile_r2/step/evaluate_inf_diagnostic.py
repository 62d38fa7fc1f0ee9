"""evaluate returns a float diagnostic that is inf (the diagnostics feed rewards and observations)."""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 1.0


def evaluate(env):
    apple = env.obj_pose("apple").p
    return {"fail": apple[:, 2] < env.table_height - 0.05, "apple_height": (env.obj_height("apple") + 1.0) / 0.0}


def compute_dense_reward(env, obs, action, info):
    return rt.reach(torch.linalg.norm(env.palm_pose.p - env.obj_pose("apple").p, dim=-1))
