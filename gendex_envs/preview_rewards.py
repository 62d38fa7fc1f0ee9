"""Default reward module for a spec held in memory (scene previews, refinement, the asset gallery).

Nothing counts as failure (success is the spec's conditions, as always); the dense reward pulls the palm towards the
first stage's target object. Committed tasks ship their own reward modules.
"""

import torch

from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    target = (env.stage_targets[0] if env.stage_targets else None) or env.object_names[0]
    reach = rt.reach(torch.linalg.norm(env.palm_pose.p - env.obj_pose(target).p, dim=-1))
    return torch.where(info["success"], torch.ones_like(reach), reach)
