# expect: no other process's scheduling changes (run with the first wall down: ordinary builtins in the worker)
# Landlock and the seccomp filter stop signals, but setpriority and sched_setaffinity of another process of the same
# user need neither: the worker could make the env's own process (its parent) nice 19 and pin it to one CPU.
import os

import torch


def evaluate(env):
    errors = []
    for attack in (lambda: os.setpriority(os.PRIO_PROCESS, {victim}, 19),
                   lambda: os.sched_setaffinity({victim}, {0})):
        try:
            attack()
        except OSError as exc:
            errors.append(exc)
    if errors:
        raise errors[0]
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)
