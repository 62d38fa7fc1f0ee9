"""PushFoamBrickToGoal, stage push_foam_brick: Push the foam brick onto the goal mark.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 3.0


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    for name in ('foam_brick', 'distractor_apple'):
        fail = fail | (env.obj_pose(name).p[:, 2] < env.table_height - 0.05)  # fell off the table
    return {"fail": fail}


def compute_dense_reward(env, obs, action, info):
    p = env.obj_pose('foam_brick').p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    reward = reach + 2.0 * rt.place(p, env.goal_pos)
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"obj_to_goal": env.goal_pos - env.obj_pose('foam_brick').p}
