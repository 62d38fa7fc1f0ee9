"""HangMugOnTree, stage release_mug: Let go of the mug: it hangs on the peg.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 5.0
UP_M = 0.15


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    for name in ('mug',):
        fail = fail | (env.obj_pose(name).p[:, 2] < env.table_height - 0.05)  # fell off the table
    force = env.agent.get_hand_group_obj_mean_force(env.obj('mug'))  # [N, 6, 1]
    return {"fail": fail, "contact": rt.contact(force), "height": env.obj_height('mug')}


def compute_dense_reward(env, obs, action, info):
    p = env.obj_pose('mug').p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    held = info["contact"] > 0.2
    up = rt.lift(info["height"], UP_M) * held
    near = rt.place(p, env.obj_pose('stand').p) * held
    reward = reach + info["contact"] + up + near
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"palm_to_obj": env.obj_pose('mug').p - env.palm_pose.p,
            "obj_to_stand": env.obj_pose('stand').p - env.obj_pose('mug').p}
