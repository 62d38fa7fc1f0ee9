# expect: a typed error naming the module, the worker and the env unharmed
# Env members asked for with hostile arguments: a 2 MB object name (a request frame over the header limit), a part
# string past the parent's bound on names (256, then 4096 characters), and an unknown object.
import torch


def evaluate(env):
    name = "x"
    for _ in range(21):
        name = name + name
    env.obj_pose(name)
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    env.hand_forces("apple", "p" * 5000)
    env.obj_pose("no_such_object")
    return torch.zeros(env.num_envs, device=env.device)
