# expect: no connection reaches the listener
import torch


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)


def evaluate(env):
    import socket
    s = socket.create_connection(("127.0.0.1", {port}), timeout=2)
    s.sendall(b"pwned")
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}
