"""PutAppleBowl, stage reach_apple: goal = the open palm at the pre-grasp point above and beside the apple.

The pre-grasp point is where the stage executor ends this stage: palm origin 0.076 m from the apple's vertical
axis and 0.084 m above its centre (measured on 5 seeds), fingertips within 0.16 m of the apple (0.136; 0.30 at
the start) and the hand open (mean tip-to-palm 0.182 m; 0.107 closed on the apple).
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 4.0
PRE_R_M = 0.076
PRE_DZ_M = 0.084
OPEN_M = 0.16


def _pregrasp(env, obj_p):
    # an apple is round: any side works, so the goal is the nearest point of the pre-grasp ring
    d = env.palm_pose.p[:, :2] - obj_p[:, :2]
    side = d / torch.linalg.norm(d, dim=-1, keepdim=True).clamp_min(1e-6)
    return torch.cat([obj_p[:, :2] + PRE_R_M * side, obj_p[:, 2:] + PRE_DZ_M], dim=-1)


def evaluate(env):
    apple = env.obj_pose("apple").p
    fell = apple[:, 2] < env.table_height - 0.05  # rolled off the table
    palm = env.palm_pose.p
    pre_dist = torch.linalg.norm(palm - _pregrasp(env, apple), dim=-1)
    tips = env.tip_positions
    tips_dist = torch.linalg.norm(tips - apple[:, None, :], dim=-1).mean(dim=1)
    openness = torch.linalg.norm(tips - palm[:, None, :], dim=-1).mean(dim=1)
    return {"fail": fell, "pregrasp_dist": pre_dist, "tips_dist": tips_dist, "openness": openness}


def compute_dense_reward(env, obs, action, info):
    reach = rt.reach(info["pregrasp_dist"], 0.1)
    tips = rt.reach(info["tips_dist"], 0.1)
    opened = rt.fraction((info["openness"] - 0.11) / (OPEN_M - 0.11))  # 0 closed fist, 1 open
    reward = 2.0 * reach + tips + 0.5 * opened
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    p = env.obj_pose("apple").p
    return {"palm_to_pregrasp": _pregrasp(env, p) - env.palm_pose.p,
            "tips_to_apple": (p[:, None, :] - env.tip_positions).flatten(1)}
