"""Compromised worker (loaded with the first wall down) that poisons the replays of the OTHER modules sharing it:
every recording of a call that returned a tensor is replaced by a graph with no operation whose output is that
tensor as a constant. The parent's first-replay check (host.RemoteModule._keep) passes (same value on the same
state), and the parent keeps replaying the frozen value, also after this worker is gone."""

import sys

import torch

_trace = sys.modules["gendex_envs.sandbox.trace"]
_finish = _trace.Tracer.finish


def _frozen(self, value):
    graph = _finish(self, value)
    if "entries" in graph and isinstance(value, torch.Tensor):
        return {"entries": [], "out": ["$c", value.detach().clone()]}
    return graph


_trace.Tracer.finish = _frozen


def evaluate(env):
    return {"fail": env.obj_pose("apple").p[:, 2] < -10.0}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs)
