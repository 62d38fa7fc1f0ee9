"""OpenCabinetLeftHingeHalf, stage open_cabinet: Pull the door open along its path, halfway, and hold
it there.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 4.0
OPEN_FRACTION = 0.5


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    return {"fail": fail, "open_fraction": env.joint_open_fraction('cabinet')}


def compute_dense_reward(env, obs, action, info):
    handle = env.handle_pos('cabinet')
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - handle, dim=-1))
    progress = rt.fraction(1.0 - (info["open_fraction"] - 0.5).abs() / 0.5)
    reward = reach + 2.0 * progress
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"palm_to_handle": env.handle_pos('cabinet') - env.palm_pose.p,
            "open_fraction": info["open_fraction"][:, None]}
