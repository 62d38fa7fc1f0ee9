"""WipeSpillRound: The café counter needs clearing: wipe the round stain clean with the sponge, so the
crumbs can be brushed off.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 5.0


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    for name in ('sponge',):
        fail = fail | (env.obj_pose(name).p[:, 2] < env.table_height - 0.05)  # fell off the table
    force = env.agent.get_hand_group_obj_mean_force(env.obj('sponge'))  # [N, 6, 1]
    return {"fail": fail, "contact": rt.contact(force), "wiped": env.wiped_share('sponge', 'spill')}


def compute_dense_reward(env, obs, action, info):
    p = env.obj_pose('sponge').p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    over = rt.place(p, env.obj_pose('spill').p) * (info["contact"] > 0.2)
    reward = reach + info["contact"] + over + 2.0 * info["wiped"]
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"palm_to_obj": env.obj_pose('sponge').p - env.palm_pose.p,
            "obj_to_area": env.obj_pose('spill').p - env.obj_pose('sponge').p, "wiped": info["wiped"][:, None]}
