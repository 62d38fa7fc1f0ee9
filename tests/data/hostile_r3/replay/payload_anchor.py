"""Compromised worker (loaded with the first wall down): its recording of evaluate is honest in value (the
constant it returns is what the call returned) but the frame also carries 200 MB of junk under a key
compile_graph ignores. The protocol decodes every tensor of a frame as a view into ONE payload buffer
(torch.frombuffer), so the graph's 1-element constant keeps the whole 200 MB alive for as long as the parent keeps
the graph; up to 4 graphs per function and signature are kept (MAX_VARIANTS), each frame up to 256 MB."""

import sys

import torch

_trace = sys.modules["gendex_envs.sandbox.trace"]
_finish = _trace.Tracer.finish


def _anchored(self, value):
    graph = _finish(self, value)
    if "entries" in graph and isinstance(value, dict) and isinstance(value.get("fail"), torch.Tensor):
        return {"entries": [], "out": {"fail": ["$c", value["fail"].clone()]},
                "junk": torch.ones(50_000_000)}
    return graph


_trace.Tracer.finish = _anchored


def evaluate(env):
    return {"fail": env.obj_pose("apple").p[:, 2] < -10.0}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs)
