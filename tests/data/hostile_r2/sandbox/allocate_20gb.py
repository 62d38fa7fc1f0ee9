# expect: the memory limit refuses it
import torch


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)


def evaluate(env):
    big = torch.empty(5_000_000_000)
    big[::1_000_000] = 1.0
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}
