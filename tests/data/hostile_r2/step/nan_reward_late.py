"""NaN reward once triggered (the test triggers it at step 25, after the probe's 20 steps)."""

import math

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 1.0


# The trigger: the first action component exactly 1.0, which random actions (the probe's) never hit;
# the test sends it at the step it chooses, so the module behaves until then without keeping any state.
def evaluate(env):
    apple = env.obj_pose("apple").p
    return {"fail": apple[:, 2] < env.table_height - 0.05, "apple_height": env.obj_height("apple")}


def compute_dense_reward(env, obs, action, info):
    reward = rt.reach(torch.linalg.norm(env.palm_pose.p - env.obj_pose("apple").p, dim=-1))
    return torch.where(action[:, 0] == 1.0, torch.full_like(reward, math.nan), reward)
