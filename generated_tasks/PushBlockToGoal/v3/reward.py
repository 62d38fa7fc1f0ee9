"""PushBlockToGoal: push the block across the table onto the goal mark, without picking it up.

Dense reward: the palm near the block, the block near the goal (both in [0, 1]); REWARD_MAX on success.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 3.0


def evaluate(env):
    block = env.obj_pose("block").p
    fell_off = block[:, 2] < env.table_height - 0.05
    return {"fail": fell_off, "block_to_goal": torch.linalg.norm(env.goal_pos[:, :2] - block[:, :2], dim=-1)}


def compute_dense_reward(env, obs, action, info):
    block = env.obj_pose("block").p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - block, dim=-1))
    progress = rt.place(block, env.goal_pos)
    reward = reach + 2.0 * progress
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"block_to_goal": env.goal_pos - env.obj_pose("block").p}
