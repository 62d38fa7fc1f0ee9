"""PutLacrosseBallInStorageBinGreen: Stow the lacrosse ball in the crate.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 5.0
LIFT_M = 0.1


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    for name in ('lacrosse_ball', 'storage_bin'):
        fail = fail | (env.obj_pose(name).p[:, 2] < env.table_height - 0.05)  # fell off the table
    return {"fail": fail, "height": env.obj_height('lacrosse_ball')}


def compute_dense_reward(env, obs, action, info):
    p = env.obj_pose('lacrosse_ball').p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    grasp = rt.contact(env.agent.get_hand_group_obj_mean_force(env.obj('lacrosse_ball')))
    lifted = rt.lift(info["height"], LIFT_M)
    carry = rt.place(p, env.obj_pose('storage_bin').p) * (lifted > 0.5)
    reward = reach + grasp + lifted + carry
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"palm_to_obj": env.obj_pose('lacrosse_ball').p - env.palm_pose.p}
