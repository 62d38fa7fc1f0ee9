# expect: not run as trusted code: a reward.py of an untrusted folder that is a link into the committed root
# This text stands for any file under generated_tasks/ that an attacker could place there without a commit (a
# promoted run's progress.csv, a `gendex generate` draft). An untrusted folder's reward.py links to it; trust must
# be judged by the folder the module was loaded from, not by where the link leads.
import torch

open("{marker}", "w").write("a linked module ran with full builtins")


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)
