"""OpenCabinet, stage pull_door: goal = the door open to at least 80 % of its open angle (the task's success).

The executor's pull ends at 0.92-0.93 of the open angle with four fingers still hooked; it starts at 0.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 5.0
OPEN_FRACTION = 0.8
MIN_FORCE_N = 0.3


def evaluate(env):
    opened = env.joint_open_fraction("cabinet")
    force = env.agent.get_hand_group_obj_mean_force(env.handle_link("cabinet"))
    fingers = (force[:, 1:5, 0] > MIN_FORCE_N).float().sum(dim=1)
    return {"open_fraction": opened, "fingers": fingers}


def compute_dense_reward(env, obs, action, info):
    tips = env.tip_positions - env.handle_pos("cabinet")[:, None, :]
    keep = rt.reach(torch.linalg.norm(tips, dim=-1).mean(dim=1), 0.05)  # stay hooked while the handle swings
    reward = keep + info["fingers"] / 4.0 + 2.0 * rt.fraction(info["open_fraction"] / OPEN_FRACTION)
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    handle = env.handle_pos("cabinet")
    return {"handle_pos": handle, "palm_to_handle": handle - env.palm_pose.p,
            "open_fraction": info["open_fraction"][:, None]}
