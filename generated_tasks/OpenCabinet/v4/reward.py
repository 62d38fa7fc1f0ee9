"""OpenCabinet: staged dense reward (palm to the handle, hook the handle, swing the door open)."""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 4.0


def evaluate(env):
    opened = env.joint_open_fraction("cabinet")
    return {"open_fraction": opened}


def compute_dense_reward(env, obs, action, info):
    handle = env.handle_pos("cabinet")  # [N, 3]
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - handle, dim=-1))
    hook = rt.contact(env.agent.get_hand_group_obj_mean_force(env.handle_link("cabinet")))
    opened = rt.fraction(info["open_fraction"])
    reward = reach + hook + 2.0 * opened
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"handle_pos": env.handle_pos("cabinet"), "palm_to_handle": env.handle_pos("cabinet")
            - env.palm_pose.p}
