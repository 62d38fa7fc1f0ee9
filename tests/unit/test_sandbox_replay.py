"""Untrusted reward modules are recorded once by the confined worker and replayed in this process
(gendex_envs.sandbox.trace / replay): the values must be exactly those the module gives, whatever its branches,
and everything a replay cannot reproduce must go to the worker."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import sapien
import torch

from gendex_envs.registry import make_env, resolve_task
from gendex_envs.reward_module import load_reward_module
from gendex_envs.sandbox import host


def _remote(module) -> host.RemoteModule:
    return next(c.cell_contents for c in module.evaluate.__closure__ if isinstance(c.cell_contents, host.RemoteModule))


def _same(a, b) -> bool:
    if isinstance(a, torch.Tensor):
        return isinstance(b, torch.Tensor) and a.dtype == b.dtype and bool(torch.equal(a, b))
    if isinstance(a, np.ndarray):
        return np.array_equal(a, b)
    if isinstance(a, dict):
        return isinstance(b, dict) and list(a) == list(b) and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, tuple | list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    return a == b


@pytest.mark.parametrize("task", ["GenDex/PutAppleBowl-v1", "GenDex/OpenCabinet-v2"])
def test_an_untrusted_copy_steps_exactly_as_the_committed_task(tmp_path, task):
    version = resolve_task(task)
    copy = tmp_path / "tasks" / version.name / version.root.name
    version.copy_to(copy)
    trusted, untrusted = (make_env(p, control_mode="pd_joint_delta_pos") for p in (version.root, copy))
    try:
        assert _same(trusted.reset(seed=3), untrusted.reset(seed=3))
        rng = np.random.default_rng(3)
        space = trusted.action_space
        for _ in range(25):
            action = rng.uniform(space.low, space.high).astype(space.dtype)
            assert _same(trusted.step(action), untrusted.step(action))
        remote = _remote(untrusted.unwrapped.judge.module)
        replayed, served = sum(remote.replays.values()), sum(remote.worker_calls.values())
        assert replayed >= 60 and served <= 4, (remote.replays, remote.worker_calls)  # 3 recordings, 1 audit at most
    finally:
        trusted.close()
        untrusted.close()


BRANCHING = '''
import torch

REWARD_MAX = 2.0


def evaluate(env):
    x = env.obj_pose("apple").p[:, 0]
    if bool((x > 0.0).any()):
        return {"fail": x > 100.0, "side": torch.ones_like(x)}
    return {"fail": x > 100.0, "side": -torch.ones_like(x), "far": x.abs()}


def compute_dense_reward(env, obs, action, info):
    positive = bool(env.obj_pose("apple").p[0, 0] > 0)
    return torch.full((env.num_envs,), 1.0 if positive else 0.5)
'''


@pytest.fixture(scope="module")
def env(reward_env):
    return reward_env


def _put_apple(env, x: float) -> None:
    apple = env.obj("apple")
    pose = env.obj_pose("apple")
    p = pose.p[0].tolist()
    apple.set_pose(sapien.Pose([x, p[1], p[2]], pose.q[0].tolist()))


def _modules(tmp_path: Path, source: str):
    path = tmp_path / "tasks" / "Branching" / "v0" / "reward.py"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(source)
    return load_reward_module(path, trusted=False), load_reward_module(path, trusted=True)


def test_branches_on_data_are_guards_and_every_outcome_is_exact(env, tmp_path):
    untrusted, trusted = _modules(tmp_path, BRANCHING)
    remote = _remote(untrusted)
    start = float(env.obj_pose("apple").p[0, 0])
    try:
        for x in [0.05, -0.05, 0.07, -0.02, 0.01, -0.03, 0.02, -0.01] * 3:
            _put_apple(env, x)
            assert _same(untrusted.evaluate(env), trusted.evaluate(env))
            assert _same(untrusted.compute_dense_reward(env, None, None, {}),
                         trusted.compute_dense_reward(env, None, None, {}))
    finally:
        _put_apple(env, start)
    # each function was recorded once per side of its branch, then replayed
    assert remote.worker_calls == {"evaluate": 2, "compute_dense_reward": 2}, remote.worker_calls
    assert remote.replays == {"evaluate": 22, "compute_dense_reward": 22}
    assert all(len(g) == 2 for g in remote.graphs.values())


NOT_REPLAYED = '''
import torch


def evaluate(env):
    x = env.obj_pose("apple").p
    near = torch.nonzero(x[0] > 0.0)
    return {"fail": x[:, 2] > 100.0, "count": torch.full((env.num_envs,), float(near.shape[0]))}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs)
'''


def test_what_a_replay_cannot_run_stays_with_the_worker(env, tmp_path):
    untrusted, trusted = _modules(tmp_path, NOT_REPLAYED)
    remote = _remote(untrusted)
    for _ in range(host.MAX_TRACES + 3):
        assert _same(untrusted.evaluate(env), trusted.evaluate(env))
    assert remote.replays == {} and remote.graphs == {}
    assert remote.worker_calls == {"evaluate": host.MAX_TRACES + 3}
    assert remote.traces_left["evaluate"] == 0  # it stopped asking for recordings


STATEFUL = '''
import torch

CALLS = [0]


def evaluate(env):
    CALLS[0] += 1
    x = env.obj_pose("apple").p[:, 2]
    return {"fail": x > 100.0, "calls": torch.full_like(x, float(CALLS[0] > 1))}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs)
'''


def test_a_module_that_differs_from_its_recording_is_caught_by_the_audit(env, tmp_path, caplog):
    """A module keeping state across calls (the static check refuses it; here it is loaded without): its
    recording bakes in the first call, the audit finds the difference and the worker serves it from then on."""
    path = tmp_path / "tasks" / "Stateful" / "v0" / "reward.py"
    path.parent.mkdir(parents=True)
    path.write_text(STATEFUL)
    module = load_reward_module(path, trusted=False, static_check=False)
    remote = _remote(module)
    values = [float(module.evaluate(env)["calls"][0]) for _ in range(host.AUDIT_AT[0] + 5)]
    assert remote.replay_off is not None and "differed" in remote.replay_off
    assert "its calls go to the worker" in caplog.text
    assert values[-4:] == [1.0] * 4  # the worker's values once the audit found it
    assert remote.graphs == {}


def test_replay_can_be_switched_off(env, tmp_path, monkeypatch):
    monkeypatch.setenv(host.REPLAY_ENV, "0")
    untrusted, trusted = _modules(tmp_path, BRANCHING)
    for _ in range(3):
        assert _same(untrusted.evaluate(env), trusted.evaluate(env))
    remote = _remote(untrusted)
    assert remote.replays == {} and remote.worker_calls == {"evaluate": 3}
