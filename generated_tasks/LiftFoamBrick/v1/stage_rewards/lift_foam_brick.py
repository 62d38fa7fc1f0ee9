"""LiftFoamBrick, stage lift_foam_brick: Lift the foam brick 10 cm.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 3.0
LIFT_M = 0.1


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    for name in ('foam_brick',):
        fail = fail | (env.obj_pose(name).p[:, 2] < env.table_height - 0.05)  # fell off the table
    force = env.agent.get_hand_group_obj_mean_force(env.obj('foam_brick'))  # [N, 6, 1]
    return {"fail": fail, "height": env.obj_height('foam_brick'), "contact": rt.contact(force)}


def compute_dense_reward(env, obs, action, info):
    reward = info["contact"] + rt.lift(info["height"], LIFT_M) * (info["contact"] > 0.2)
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"height": info["height"][:, None], "palm_to_obj": env.obj_pose('foam_brick').p - env.palm_pose.p}
