# expect: reading /etc/passwd is refused
import torch


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)


def evaluate(env):
    text = open("/etc/passwd").read()
    torch.tensor(float(len(text)))
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}
