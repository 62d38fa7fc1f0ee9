"""PutAppleBowl, stage grasp_apple: goal = a finger grasp that can carry the apple: the thumb and at least three
fingers pressing on it, and the palm not pushing it into the table.

The stage drives the hand only, so the lift is left to move_to_bowl's arm. Contact is a hand group's mean force on
the apple above 0.3 N. At the executor's end of this stage the thumb pushes 4.2-6.6 N, every finger 0.8-2.1 N and
the palm 0 N (seeds 0-2); at its start nothing touches. The palm limit is measured too: a PPO policy trained with
contact alone (thumb + two fingers) learned to press the apple into the table with the palm (39-65 N) and two
fingers, a hold that met the goal but lost the apple as soon as the arm lifted (0 of 192 carries reached the bowl).
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 4.0
MIN_FORCE_N = 0.3
PALM_MAX_N = 10.0


def evaluate(env):
    fell = env.obj_pose("apple").p[:, 2] < env.table_height - 0.05  # rolled off the table
    force = env.agent.get_hand_group_obj_mean_force(env.obj("apple"))[..., 0]  # [N, 6] th ff mf rf lf palm
    return {"fail": fell, "contact": rt.contact(force[..., None], MIN_FORCE_N),
            "palm_press": (force[:, 5] / (4.0 * PALM_MAX_N)).clamp(0.0, 1.0)}


def compute_dense_reward(env, obs, action, info):
    tips = rt.tips_reach(env.tip_positions, env.obj_pose("apple").p, 0.05)
    reward = tips + 2.0 * info["contact"] - info["palm_press"]
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    force = env.agent.get_hand_group_obj_mean_force(env.obj("apple"))[..., 0]
    return {"tips_to_apple": (env.obj_pose("apple").p[:, None, :] - env.tip_positions).flatten(1),
            "hand_force": force.clamp(max=10.0) / 10.0}
