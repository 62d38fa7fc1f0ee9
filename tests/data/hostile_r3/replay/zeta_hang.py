"""Compromised worker (loaded with the first wall down): every recording it sends is one call of
torch.special.zeta, an allow-listed elementwise function, on one element. Its stated shape is true and its work,
as replay._work counts it, is 3 elements; but zeta(2, q) for a negative non-integer q loops about -q times
(Cephes's Hurwitz zeta), so the parent's first replay (host.RemoteModule._keep) runs for seconds, or for hours
with q = -1e13 + 0.5."""

import sys

import torch

Q = -1e8 + 0.5
FORGED = {
    "entries": [["O", "torch.special.zeta", ["$u", ["$c", torch.tensor([2.0], dtype=torch.float64)],
                                             ["$c", torch.tensor([Q], dtype=torch.float64)]], {},
                 ["T", "float64", [1]]]],
    "out": {"fail": ["$r", 0, None]},
}
sys.modules["gendex_envs.sandbox.trace"].Tracer.finish = lambda self, value: FORGED


def evaluate(env):
    return {"fail": env.obj_pose("apple").p[:, 2] < -10.0}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs)
