"""PickUpBottle: staged dense reward (fingertips to the bottle, thumb-opposed contact, lift 10 cm)."""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 4.0
LIFT_M = 0.1


def evaluate(env):
    height = env.obj_height("bottle")
    q = env.obj_pose("bottle").q  # [N, 4] wxyz
    up_z = 1.0 - 2.0 * (q[:, 1] ** 2 + q[:, 2] ** 2)  # z component of the bottle's axis
    toppled = (up_z < 0.5) & (height < 0.02)  # tilted past 60 degrees while still on the table
    return {"fail": toppled, "bottle_height": height}


def compute_dense_reward(env, obs, action, info):
    bottle = env.obj_pose("bottle").p
    reach = rt.tips_reach(env.tip_positions, bottle + torch.tensor([0.0, 0.0, 0.08], device=env.device))
    grasp = rt.contact(env.agent.get_hand_group_obj_mean_force(env.obj("bottle")))
    lifted = rt.lift(info["bottle_height"], LIFT_M)
    reward = reach + grasp + 2.0 * lifted * (grasp > 0)
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"tips_to_bottle": (env.tip_positions - env.obj_pose("bottle").p[:, None, :]).flatten(1)}
