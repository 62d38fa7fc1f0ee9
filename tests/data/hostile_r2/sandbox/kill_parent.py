# expect: no signal reaches another process
import torch


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)


def evaluate(env):
    import os, signal
    os.kill({victim}, signal.SIGTERM)
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}
