"""PutAppleBowl: staged dense reward (reach the apple, grasp it, lift it, carry it over the bowl, release)."""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 5.0
LIFT_M = 0.1


def evaluate(env):
    apple = env.obj_pose("apple").p
    fell_off = apple[:, 2] < env.table_height - 0.05  # rolled off the table
    return {"fail": fell_off, "apple_height": env.obj_height("apple")}


def compute_dense_reward(env, obs, action, info):
    apple = env.obj_pose("apple").p  # [N, 3]
    bowl = env.obj_pose("bowl").p
    palm = env.palm_pose.p
    reach = rt.reach(torch.linalg.norm(palm - apple, dim=-1))
    grasp = rt.contact(env.agent.get_hand_group_obj_mean_force(env.obj("apple")))
    lifted = rt.lift(info["apple_height"], LIFT_M)
    carry = rt.place(apple, bowl) * (lifted > 0.5)
    reward = reach + grasp + lifted + carry
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"apple_to_bowl": env.obj_pose("bowl").p - env.obj_pose("apple").p}
