"""PickUpBottle, stage grasp_bottle: goal = thumb and at least two fingers pressing on the upright bottle.

Contact is a hand group's mean force on the bottle above 0.3 N; at the executor's end of this stage the thumb
pushes 6-10 N and every finger 0.7-8 N, at its start nothing touches.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 4.0
MIN_FORCE_N = 0.3


def evaluate(env):
    pose = env.obj_pose("bottle")
    height = env.obj_height("bottle")
    up_z = 1.0 - 2.0 * (pose.q[:, 1] ** 2 + pose.q[:, 2] ** 2)
    toppled = (up_z < 0.5) & (height < 0.02)  # lying on the table: the hand alone cannot stand it up
    force = env.agent.get_hand_group_obj_mean_force(env.obj("bottle"))  # [N, 6, 1] th ff mf rf lf palm
    return {"fail": toppled, "contact": rt.contact(force, MIN_FORCE_N)}


def compute_dense_reward(env, obs, action, info):
    tips = rt.tips_reach(env.tip_positions, env.obj_pose("bottle").p, 0.05)
    reward = tips + 2.0 * info["contact"]
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    force = env.agent.get_hand_group_obj_mean_force(env.obj("bottle"))[..., 0]
    return {"tips_to_bottle": (env.obj_pose("bottle").p[:, None, :] - env.tip_positions).flatten(1),
            "hand_force": force.clamp(max=10.0) / 10.0}
