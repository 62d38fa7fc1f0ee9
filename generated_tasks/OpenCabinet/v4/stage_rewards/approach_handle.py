"""OpenCabinet, stage approach_handle: goal = the open hand in front of the handle, fingers across the bar.

The executor ends this stage with the palm origin 0.129 m from the handle's grip point, the fingertips 0.086 m
from it on average and the hand open (mean tip-to-palm 0.182 m); at the start they are 0.33-0.36 m and
0.18-0.22 m away. Thresholds: palm <= 0.15 m, tips <= 0.11 m, open >= 0.16 m.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 4.0
OPEN_M = 0.16


def evaluate(env):
    handle = env.handle_pos("cabinet")
    palm = env.palm_pose.p
    tips = env.tip_positions
    palm_dist = torch.linalg.norm(palm - handle, dim=-1)
    tips_dist = torch.linalg.norm(tips - handle[:, None, :], dim=-1).mean(dim=1)
    openness = torch.linalg.norm(tips - palm[:, None, :], dim=-1).mean(dim=1)
    return {"palm_dist": palm_dist, "tips_dist": tips_dist, "openness": openness}


def compute_dense_reward(env, obs, action, info):
    opened = rt.fraction((info["openness"] - 0.11) / (OPEN_M - 0.11))  # a closed hand cannot hook the bar
    reward = 1.5 * rt.reach(info["palm_dist"], 0.1) + 1.5 * rt.reach(info["tips_dist"], 0.1) + 0.5 * opened
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    handle = env.handle_pos("cabinet")
    return {"handle_pos": handle, "palm_to_handle": handle - env.palm_pose.p,
            "tips_to_handle": (handle[:, None, :] - env.tip_positions).flatten(1)}
