"""OpenMicrowaveStandard, stage open_microwave: Pull the door open along its path.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 4.0
OPEN_FRACTION = 0.8


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    return {"fail": fail, "open_fraction": env.joint_open_fraction('microwave')}


def compute_dense_reward(env, obs, action, info):
    handle = env.handle_pos('microwave')
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - handle, dim=-1))
    progress = rt.fraction(info["open_fraction"] / OPEN_FRACTION)
    reward = reach + 2.0 * progress
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"palm_to_handle": env.handle_pos('microwave') - env.palm_pose.p,
            "open_fraction": info["open_fraction"][:, None]}
