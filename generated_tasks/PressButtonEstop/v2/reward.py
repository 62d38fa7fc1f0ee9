"""PressButtonEstop: Give the button a firm press, to make space for the cake.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 4.0


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    return {"fail": fail, "open_fraction": env.joint_open_fraction('button')}


def compute_dense_reward(env, obs, action, info):
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - env.handle_pos('button'), dim=-1))
    reward = reach + 2.0 * rt.fraction(info["open_fraction"])
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"palm_to_handle": env.handle_pos('button') - env.palm_pose.p}
