"""CloseTrashCanTallThenLiftBottle: The fox raided the garden last night: push the open lid of the tall
waste bin closed, then grab the bottle and hoist it well up off the counter, so the crumbs can be
brushed off.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 7.0
LIFT_M = 0.1
PART_DONE_PLACE = 0.8


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    for name in ('bottle', 'distractor_softball'):
        fail = fail | (env.obj_pose(name).p[:, 2] < env.table_height - 0.05)  # fell off the table
    return {"fail": fail, "open_fraction_0": env.joint_open_fraction('trash_can'), "height_1": env.obj_height('bottle')}


def compute_dense_reward(env, obs, action, info):
    reward = torch.zeros(env.num_envs, device=env.device)
    gate = torch.ones(env.num_envs, device=env.device)
    d = rt.fraction((1.0 - info["open_fraction_0"]) / 0.9)
    done = d > 0.99
    reward = reward + gate * torch.where(done, torch.full_like(d, 2.0), 2.0 * d)
    gate = gate * done
    p = env.obj_pose('bottle').p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    grasp = rt.contact(env.agent.get_hand_group_obj_mean_force(env.obj('bottle')))
    lifted = rt.lift(info["height_1"], LIFT_M)
    carry = torch.zeros_like(reach)
    done = lifted > 0.99
    reward = reward + gate * torch.where(done, torch.full_like(reach, 4.0), reach + grasp + lifted + carry)
    gate = gate * done
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)
