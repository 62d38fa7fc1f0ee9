# expect: the wall-clock limit stops it
import torch


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)


def evaluate(env):
    import time
    time.sleep(1_000_000)
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}
