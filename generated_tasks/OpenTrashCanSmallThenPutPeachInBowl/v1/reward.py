"""OpenTrashCanSmallThenPutPeachInBowl: The vegetables have just been trimmed: open the lid of the
small waste bin, then store the peach inside the mixing bowl, so the wasps leave it alone.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 7.0
LIFT_M = 0.1
PART_DONE_PLACE = 0.8


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    for name in ('peach', 'bowl', 'distractor_plum'):
        fail = fail | (env.obj_pose(name).p[:, 2] < env.table_height - 0.05)  # fell off the table
    return {"fail": fail, "open_fraction_0": env.joint_open_fraction('trash_can'), "height_1": env.obj_height('peach')}


def compute_dense_reward(env, obs, action, info):
    reward = torch.zeros(env.num_envs, device=env.device)
    gate = torch.ones(env.num_envs, device=env.device)
    d = rt.fraction(info["open_fraction_0"] / 0.5)
    done = d > 0.99
    reward = reward + gate * torch.where(done, torch.full_like(d, 2.0), 2.0 * d)
    gate = gate * done
    p = env.obj_pose('peach').p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    grasp = rt.contact(env.agent.get_hand_group_obj_mean_force(env.obj('peach')))
    lifted = rt.lift(info["height_1"], LIFT_M)
    carry = rt.place(p, env.obj_pose('bowl').p) * (lifted > 0.5)
    over = rt.place(p, env.obj_pose('bowl').p)
    done = (over > PART_DONE_PLACE) & (info["height_1"] < LIFT_M / 2)
    reward = reward + gate * torch.where(done, torch.full_like(reach, 4.0), reach + grasp + lifted + carry)
    gate = gate * done
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)
