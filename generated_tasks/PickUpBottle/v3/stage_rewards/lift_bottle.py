"""PickUpBottle, stage lift_bottle: goal = the bottle, still held, at least 10 cm above its start height.

10 cm is the task's success height; the executor ends its grasp with the bottle 0.145-0.149 m up, thumb and
fingers all in contact (above 0.3 N).
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 4.0
LIFT_M = 0.1
MIN_FORCE_N = 0.3


def evaluate(env):
    pose = env.obj_pose("bottle")
    height = env.obj_height("bottle")
    up_z = 1.0 - 2.0 * (pose.q[:, 1] ** 2 + pose.q[:, 2] ** 2)
    toppled = (up_z < 0.5) & (height < 0.02)  # dropped and lying on the table
    force = env.agent.get_hand_group_obj_mean_force(env.obj("bottle"))
    touching = force[..., 0] > MIN_FORCE_N
    held = touching[:, 0] & (touching[:, 1:5].sum(dim=1) >= 2)
    return {"fail": toppled, "height": height, "held": held, "contact": rt.contact(force, MIN_FORCE_N)}


def compute_dense_reward(env, obs, action, info):
    # height only pays while held, so throwing the bottle up is not rewarded
    reward = info["contact"] + 2.0 * rt.lift(info["height"], LIFT_M) * info["held"]
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    return {"height": info["height"][:, None],
            "tips_to_bottle": (env.obj_pose("bottle").p[:, None, :] - env.tip_positions).flatten(1)}
