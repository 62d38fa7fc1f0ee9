"""OpenTrashCanSmallThenPutPeachInBowl, stage open_trash_can: Lift the lid along its arc until it is
open.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 4.0
OPEN_FRACTION = 0.5


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    for name in ('peach', 'bowl', 'distractor_plum'):
        fail = fail | (env.obj_pose(name).p[:, 2] < env.table_height - 0.05)  # fell off the table
    return {"fail": fail, "open_fraction": env.joint_open_fraction('trash_can')}


def compute_dense_reward(env, obs, action, info):
    handle = env.handle_pos('trash_can')
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - handle, dim=-1))
    progress = rt.fraction(info["open_fraction"] / OPEN_FRACTION)
    reward = reach + 2.0 * progress
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"palm_to_handle": env.handle_pos('trash_can') - env.palm_pose.p,
            "open_fraction": info["open_fraction"][:, None]}
