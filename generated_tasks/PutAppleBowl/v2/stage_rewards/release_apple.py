"""PutAppleBowl, stage release_apple: goal = the apple inside the bowl and no part of the hand touching it.

Inside is the task's own condition (env.spec_success()); contact is a hand group's mean force above 0.3 N. The
executor's release ends with the apple 0.028-0.046 m from the bowl's axis and no contact; at its start the apple
is held 0.15 m above the bowl (not inside).
"""

import torch

from gendex_envs import reward_terms as rt

REWARD_MAX = 3.0
MIN_FORCE_N = 0.3
OVER_R_M = 0.075


def evaluate(env):
    apple = env.obj_pose("apple").p
    bowl = env.obj_pose("bowl").p
    xy = torch.linalg.norm((apple - bowl)[:, :2], dim=-1)
    # down on the table beside the bowl (or off it): a hand-only stage cannot pick it up again
    fail = (apple[:, 2] < env.table_height - 0.05) | ((env.obj_height("apple") < 0.01) & (xy > OVER_R_M))
    force = env.agent.get_hand_group_obj_mean_force(env.obj("apple"))
    inside = env.spec_success()
    return {"fail": fail, "inside": inside, "bowl_xy": xy, "contact": rt.contact(force, MIN_FORCE_N)}


def compute_dense_reward(env, obs, action, info):
    reward = rt.reach(info["bowl_xy"], 0.05) + (1.0 - info["contact"]) + info["inside"].float()
    return torch.where(info["success"], torch.full_like(reward, REWARD_MAX), reward)


def _get_obs_extra(env, info):
    force = env.agent.get_hand_group_obj_mean_force(env.obj("apple"))[..., 0]
    return {"apple_to_bowl": env.obj_pose("bowl").p - env.obj_pose("apple").p,
            "hand_force": force.clamp(max=10.0) / 10.0}
