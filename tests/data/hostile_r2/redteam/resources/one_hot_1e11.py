# expect: a typed error within the call's limit, the env and later modules unharmed
# Only allow-listed names, but unbounded work: `x = torch.nn.functional.one_hot(torch.tensor([10**11]))`.
import torch


def _deeper(n):
    return _deeper(n + 1)


def evaluate(env):
    x = torch.nn.functional.one_hot(torch.tensor([10**11]))
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device) | (x == 0).any()}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)
