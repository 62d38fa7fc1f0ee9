"""FlipTumbler, stage flip_tumbler: Turn the tumbler upside down and lower it to the table.

Composed by GenDex's offline author from the vetted terms of gendex_envs.reward_terms.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 5.0
UP_M = 0.15


def _up(q):
    """[N, 3] the world direction of the object's own z axis for unit quaternions q [N, 4] (wxyz)."""
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return torch.stack([2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y)], dim=-1)


def evaluate(env):
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    for name in ('tumbler',):
        fail = fail | (env.obj_pose(name).p[:, 2] < env.table_height - 0.05)  # fell off the table
    force = env.agent.get_hand_group_obj_mean_force(env.obj('tumbler'))  # [N, 6, 1]
    turned = (1.0 - (_up(env.obj_pose('tumbler').q) * _up(env.init_obj_quat('tumbler'))).sum(dim=-1)) / 2.0
    return {"fail": fail, "contact": rt.contact(force), "height": env.obj_height('tumbler'), "turned": turned}


def compute_dense_reward(env, obs, action, info):
    p = env.obj_pose('tumbler').p
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - p, dim=-1))
    up = rt.lift(info["height"], UP_M) * (info["contact"] > 0.2)
    reward = reach + info["contact"] + up + 2.0 * info["turned"]
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"palm_to_obj": env.obj_pose('tumbler').p - env.palm_pose.p, "turned": info["turned"][:, None]}
