"""PutPlumInBowlLargeThenPutToyDuckInBowlLarge, stage grasp_toy_duck: Close the fingers around the toy
duck.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 4.0


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    for name in ('plum', 'bowl', 'toy_duck'):
        fail = fail | (env.obj_pose(name).p[:, 2] < env.table_height - 0.05)  # fell off the table
    force = env.agent.get_hand_group_obj_mean_force(env.obj('toy_duck'))  # [N, 6, 1]
    return {"fail": fail, "contact": rt.contact(force)}


def compute_dense_reward(env, obs, action, info):
    p = env.obj_pose('toy_duck').p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    tips = rt.tips_reach(env.tip_positions, p, 0.05)
    reward = reach + tips + info["contact"]
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    pose = env.obj_pose('toy_duck')
    return {"palm_to_obj": pose.p - env.palm_pose.p, "obj_pose": torch.cat([pose.p, pose.q], dim=-1)}
