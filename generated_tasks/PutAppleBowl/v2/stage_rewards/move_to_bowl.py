"""PutAppleBowl, stage move_to_bowl: goal = the held apple above the bowl's footprint, ready to drop.

Above the footprint: apple centre within 0.075 m (the bowl's half width) of the bowl's axis and 0.08-0.22 m above
the bowl's origin (rim at 0.063 m). The executor ends this stage at 0.046-0.054 m / 0.149-0.154 m, thumb and
fingers still in contact; at its start the apple is 0.26-0.31 m from the bowl's axis.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 4.0
DZ_MIN_M = 0.08
MIN_FORCE_N = 0.3


def evaluate(env):
    apple = env.obj_pose("apple").p
    bowl = env.obj_pose("bowl").p
    fell = apple[:, 2] < env.table_height - 0.05
    force = env.agent.get_hand_group_obj_mean_force(env.obj("apple"))
    touching = force[..., 0] > MIN_FORCE_N
    held = touching[:, 0] & (touching[:, 1:5].sum(dim=1) >= 2)
    xy = torch.linalg.norm((apple - bowl)[:, :2], dim=-1)
    dz = apple[:, 2] - bowl[:, 2]
    return {"fail": fell, "held": held, "bowl_xy": xy, "bowl_dz": dz, "contact": rt.contact(force, MIN_FORCE_N)}


def compute_dense_reward(env, obs, action, info):
    # carrying pays only while held; the height term keeps the apple clear of the rim on the way
    carry = rt.reach(info["bowl_xy"], 0.1) + rt.fraction(info["bowl_dz"] / DZ_MIN_M)
    reward = info["contact"] + carry * info["held"]
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"apple_to_bowl": env.obj_pose("bowl").p - env.obj_pose("apple").p,
            "palm_to_apple": env.obj_pose("apple").p - env.palm_pose.p}
