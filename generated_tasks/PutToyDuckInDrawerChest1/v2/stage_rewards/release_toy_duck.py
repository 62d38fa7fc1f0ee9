"""PutToyDuckInDrawerChest1, stage release_toy_duck: Open the hand to let go of the toy duck.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 3.0


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    for name in ('toy_duck',):
        fail = fail | (env.obj_pose(name).p[:, 2] < env.table_height - 0.05)  # fell off the table
    force = env.agent.get_hand_group_obj_mean_force(env.obj('toy_duck'))  # [N, 6, 1]
    return {"fail": fail, "contact": rt.contact(force)}


def compute_dense_reward(env, obs, action, info):
    place = rt.place(env.obj_pose('toy_duck').p, env.holds_point('drawer_chest', 'drawer_0_slide'))
    reward = 2.0 * place + (1.0 - info['contact']) * (place > 0.8)
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"obj_to_target": env.holds_point('drawer_chest', 'drawer_0_slide') - env.obj_pose('toy_duck').p}
