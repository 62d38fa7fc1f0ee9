"""SetTwoBallsOnTray: Set the two balls down on the tray.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 9.0
LIFT_M = 0.1
PART_DONE_PLACE = 0.8


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    for name in ('softball', 'tray', 'baseball'):
        fail = fail | (env.obj_pose(name).p[:, 2] < env.table_height - 0.05)  # fell off the table
    return {"fail": fail, "height_0": env.obj_height('softball'), "height_1": env.obj_height('baseball')}


def compute_dense_reward(env, obs, action, info):
    reward = torch.zeros(env.num_envs, device=env.device)
    gate = torch.ones(env.num_envs, device=env.device)
    p = env.obj_pose('softball').p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    grasp = rt.contact(env.agent.get_hand_group_obj_mean_force(env.obj('softball')))
    lifted = rt.lift(info["height_0"], LIFT_M)
    carry = rt.place(p, env.obj_pose('tray').p) * (lifted > 0.5)
    over = rt.place(p, env.obj_pose('tray').p)
    done = (over > PART_DONE_PLACE) & (info["height_0"] < LIFT_M / 2)
    reward = reward + gate * torch.where(done, torch.full_like(reach, 4.0), reach + grasp + lifted + carry)
    gate = gate * done
    p = env.obj_pose('baseball').p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    grasp = rt.contact(env.agent.get_hand_group_obj_mean_force(env.obj('baseball')))
    lifted = rt.lift(info["height_1"], LIFT_M)
    carry = rt.place(p, env.obj_pose('tray').p) * (lifted > 0.5)
    over = rt.place(p, env.obj_pose('tray').p)
    done = (over > PART_DONE_PLACE) & (info["height_1"] < LIFT_M / 2)
    reward = reward + gate * torch.where(done, torch.full_like(reach, 4.0), reach + grasp + lifted + carry)
    gate = gate * done
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)
