"""CloseCabinetLeftHingeThenSetBlockLargeOnCuttingBoard: Spring cleaning has begun: swing the open left-hinged cupboard door closed, then lay the toy block on the chopping board.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 7.0
LIFT_M = 0.1


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    for name in ('block', 'cutting_board'):
        fail = fail | (env.obj_pose(name).p[:, 2] < env.table_height - 0.05)  # fell off the table
    return {"fail": fail, "open_fraction": env.joint_open_fraction('cabinet'), "height": env.obj_height('block')}


def compute_dense_reward(env, obs, action, info):
    first = rt.fraction((1.0 - info["open_fraction"]) / 0.9)
    p = env.obj_pose('block').p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    grasp = rt.contact(env.agent.get_hand_group_obj_mean_force(env.obj('block')))
    lifted = rt.lift(info["height"], LIFT_M)
    carry = rt.place(p, env.obj_pose('cutting_board').p) * (lifted > 0.5)
    reward = 2.0 * first + (first > 0.99) * (reach + grasp + lifted + carry)
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"palm_to_obj": env.obj_pose('block').p - env.palm_pose.p, "open_fraction": info["open_fraction"][:, None]}
