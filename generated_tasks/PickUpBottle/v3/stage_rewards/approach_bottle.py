"""PickUpBottle, stage approach_bottle: goal = the open palm at the pre-grasp point beside the bottle.

The pre-grasp point is where the stage executor ends this stage: palm origin 0.11 m from the bottle's axis and
0.12 m above its origin (measured 0.109 / 0.123 on 5 seeds), on whichever side the palm comes from, fingertips
within 0.17 m of the bottle (0.148; 0.31 at the start) and the hand open (mean tip-to-palm 0.177 m; 0.117 closed).
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 4.0
PRE_R_M = 0.11
PRE_DZ_M = 0.12
OPEN_M = 0.16


def _pregrasp(env, obj_p):
    # the side is free (any yaw grasps a cylinder), so the goal is the nearest point of the pre-grasp ring
    d = env.palm_pose.p[:, :2] - obj_p[:, :2]
    side = d / torch.linalg.norm(d, dim=-1, keepdim=True).clamp_min(1e-6)
    return torch.cat([obj_p[:, :2] + PRE_R_M * side, obj_p[:, 2:] + PRE_DZ_M], dim=-1)


def evaluate(env):
    pose = env.obj_pose("bottle")
    height = env.obj_height("bottle")
    up_z = 1.0 - 2.0 * (pose.q[:, 1] ** 2 + pose.q[:, 2] ** 2)  # z component of the bottle's axis
    toppled = (up_z < 0.5) & (height < 0.02)
    palm = env.palm_pose.p
    pre_dist = torch.linalg.norm(palm - _pregrasp(env, pose.p), dim=-1)
    tips = env.tip_positions
    tips_dist = torch.linalg.norm(tips - pose.p[:, None, :], dim=-1).mean(dim=1)
    openness = torch.linalg.norm(tips - palm[:, None, :], dim=-1).mean(dim=1)
    return {"fail": toppled, "pregrasp_dist": pre_dist, "tips_dist": tips_dist, "openness": openness}


def compute_dense_reward(env, obs, action, info):
    reach = rt.reach(info["pregrasp_dist"], 0.1)
    tips = rt.reach(info["tips_dist"], 0.1)
    opened = rt.fraction((info["openness"] - 0.11) / (OPEN_M - 0.11))  # 0 closed fist, 1 open
    reward = 2.0 * reach + tips + 0.5 * opened
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    p = env.obj_pose("bottle").p
    return {"palm_to_pregrasp": _pregrasp(env, p) - env.palm_pose.p,
            "tips_to_bottle": (p[:, None, :] - env.tip_positions).flatten(1)}
