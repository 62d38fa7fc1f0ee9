"""OpenTrashCan: Lift the trash can's lid open by its tab.

Dense reward: the palm near the handle (its grip point),
the lid's open fraction (both in [0, 1]); REWARD_MAX on success.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 3.0


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device),
            "open_fraction": env.joint_open_fraction("trash_can")}


def compute_dense_reward(env, obs, action, info):
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - env.handle_pos("trash_can"), dim=-1))
    progress = rt.fraction(info["open_fraction"])
    reward = reach + 2.0 * progress
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"palm_to_handle": env.handle_pos("trash_can") - env.palm_pose.p,
            "open_fraction": info["open_fraction"][:, None]}
