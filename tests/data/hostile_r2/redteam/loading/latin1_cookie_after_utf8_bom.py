# coding: latin-1
import torch
#+AAo-open('{marker}', 'w').write('hidden utf-7 line ran')


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)
