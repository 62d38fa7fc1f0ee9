# expect: the parent's work per call stays bounded (or a typed error): no unbounded growth of prefetched env reads
# hand_forces(name, part, joint) ignores `part` unless it is "handle", yet the sandbox's parent files every distinct
# (name, part, joint) a call asked for and computes all of them again on every later call. 1500 new meaningless part
# strings per call, varied by the robot's state, make each step cost more than the last, outside the call's limit.
import torch


def evaluate(env):
    total = torch.zeros(env.num_envs, device=env.device)
    seed = int(env.agent.robot.get_qpos()[0, 0].item() * 1000000000)
    for i in range(1500):
        total = total + env.hand_forces("apple", "p" + str(seed + i)).sum(-1)
    return {"fail": total > 1e9}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)
