"""PourBeadsFromTumblerIntoBowl: The washing-up has been dried and stacked: empty the drinking glass of
ceramic beads into the bowl, so the table can be wiped.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 5.0


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    for name in ('tumbler', 'bowl'):
        fail = fail | (env.obj_pose(name).p[:, 2] < env.table_height - 0.05)  # fell off the table
    force = env.agent.get_hand_group_obj_mean_force(env.obj('tumbler'))  # [N, 6, 1]
    return {"fail": fail, "contact": rt.contact(force), "poured": env.poured_share('tumbler', 'bowl')}


def compute_dense_reward(env, obs, action, info):
    p = env.obj_pose('tumbler').p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    near = rt.place(p, env.obj_pose('bowl').p) * (info["contact"] > 0.2)
    reward = reach + info["contact"] + near + 2.0 * info["poured"]
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"palm_to_obj": env.obj_pose('tumbler').p - env.palm_pose.p,
            "obj_to_into": env.obj_pose('bowl').p - env.obj_pose('tumbler').p, "poured": info["poured"][:, None]}
