# expect: no process runs (no marker)
import torch


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)


def evaluate(env):
    import os
    os.system("touch {marker}")
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}
