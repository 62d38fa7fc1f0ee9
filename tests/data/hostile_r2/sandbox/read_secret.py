# expect: reading a file outside the Python installation (a user file) is refused
import torch


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)


def evaluate(env):
    text = open("{secret}").read()
    torch.tensor(float(len(text)))
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}
