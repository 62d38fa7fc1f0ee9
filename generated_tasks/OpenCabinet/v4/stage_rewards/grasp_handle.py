"""OpenCabinet, stage grasp_handle: goal = at least three fingers pressing on the handle link, curled round the bar.

Contact alone also holds for a hand flat on the door, so the fingertips must be curled in: mean tip-to-grip-point
distance <= 0.07 m. The executor's hook ends with ff/mf/rf/lf at 12-14 / 11-13 / 5-8 / 1.5 N and the tips 0.047 m
from the grip point; at its start nothing touches and the tips are 0.086 m away.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 3.0
MIN_FORCE_N = 0.3


def evaluate(env):
    handle = env.handle_pos("cabinet")
    force = env.agent.get_hand_group_obj_mean_force(env.handle_link("cabinet"))  # [N, 6, 1] th ff mf rf lf palm
    fingers = (force[:, 1:5, 0] > MIN_FORCE_N).float().sum(dim=1)  # a hook needs no thumb
    tips_dist = torch.linalg.norm(env.tip_positions - handle[:, None, :], dim=-1).mean(dim=1)
    return {"fingers": fingers, "tips_dist": tips_dist}


def compute_dense_reward(env, obs, action, info):
    reward = rt.reach(info["tips_dist"], 0.05) + info["fingers"] / 4.0
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    handle = env.handle_pos("cabinet")
    force = env.agent.get_hand_group_obj_mean_force(env.handle_link("cabinet"))[..., 0]
    return {"tips_to_handle": (handle[:, None, :] - env.tip_positions).flatten(1),
            "hand_force": force.clamp(max=10.0) / 10.0}
