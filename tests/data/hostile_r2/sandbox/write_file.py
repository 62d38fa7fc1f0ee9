# expect: no file; writes are refused
import torch


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)


def evaluate(env):
    open("{marker}", "w").write("pwned")
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}
