"""TakeBottleOutOfBowl: A food photographer is styling a shoot: get the bottle out of the bowl.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 5.0
LIFT_M = 0.1


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    for name in ('bottle', 'bowl'):
        fail = fail | (env.obj_pose(name).p[:, 2] < env.table_height - 0.05)  # fell off the table
    return {"fail": fail, "height": env.obj_height('bottle')}


def compute_dense_reward(env, obs, action, info):
    p = env.obj_pose('bottle').p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    grasp = rt.contact(env.agent.get_hand_group_obj_mean_force(env.obj('bottle')))
    lifted = rt.lift(info["height"], LIFT_M)
    carry = rt.place(p, env.obj_pose('bowl').p + torch.tensor([[-0.1980, -0.0000, 0.0]], device=env.device)) * (lifted > 0.5)
    reward = reach + grasp + lifted + carry
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"palm_to_obj": env.obj_pose('bottle').p - env.palm_pose.p}
