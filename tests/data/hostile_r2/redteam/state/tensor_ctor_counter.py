# expect: state across calls through uninitialised memory: torch.Tensor(n) is torch.empty(n) by another name
# Each call reads a counter the previous call left in freed memory (past the allocator's 16 bytes of bookkeeping),
# then writes counter + 1 into a same-sized tensor that is freed when the call returns; the next call's
# torch.Tensor(4096) gets that block back. Such a module can count its calls and change behaviour after the probe.
import torch

SIZE = 4096


def _remembered():
    mem = torch.Tensor(SIZE)
    return torch.where(mem[11] == 12345.0, mem[10] + 1.0, torch.zeros(()))


def evaluate(env):
    count = _remembered()
    keep = torch.zeros(SIZE)
    keep[10] = count
    keep[11] = 12345.0
    fail = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    return {"fail": fail, "count": count.expand(env.num_envs).to(env.device) + keep[11] * 0.0}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)
