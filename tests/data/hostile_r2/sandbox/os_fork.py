# expect: no process is forked (no marker)
import torch


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)


def evaluate(env):
    import os
    pid = os.fork()
    if pid == 0:
        open("{marker}", "w").write("child")
        os._exit(0)
    os.waitpid(pid, 0)
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}
