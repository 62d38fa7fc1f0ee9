"""PutAppleBowl, stage grasp_apple: success = thumb and at least two fingers pressing on the apple.

The stage drives the hand only, so the lift is left to move_to_bowl's arm. Contact is a hand group's mean force on
the apple above 0.3 N; at the executor's end of this stage the thumb pushes 1.9-3.8 N and every finger 0.8-1.9 N,
at its start nothing touches.
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 4.0
MIN_FORCE_N = 0.3


def evaluate(env):
    fell = env.obj_pose("apple").p[:, 2] < env.table_height - 0.05  # rolled off the table
    force = env.agent.get_hand_group_obj_mean_force(env.obj("apple"))  # [N, 6, 1] th ff mf rf lf palm
    touching = force[..., 0] > MIN_FORCE_N
    held = touching[:, 0] & (touching[:, 1:5].sum(dim=1) >= 2)  # thumb opposing two fingers
    return {"success": held & ~fell, "fail": fell, "contact": rt.contact(force, MIN_FORCE_N)}


def compute_dense_reward(env, obs, action, info):
    tips = rt.tips_reach(env.tip_positions, env.obj_pose("apple").p, 0.05)
    reward = tips + 2.0 * info["contact"]
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    force = env.agent.get_hand_group_obj_mean_force(env.obj("apple"))[..., 0]
    return {"tips_to_apple": (env.obj_pose("apple").p[:, None, :] - env.tip_positions).flatten(1),
            "hand_force": force.clamp(max=10.0) / 10.0}
