"""Reward outputs are checked on every step, not only in the reward probe's first 20 (issue 43, "checks only in the
probe"): a module that behaves until it is triggered, then returns NaN, inf or a wrong shape, or that returns keys
other tools read as success, or that replaces the env's own observations, is stopped with a RewardOutputError that
names it; and reward code cannot read the step count to wait out the probe.

Each payload in ``tests/data/hostile_r2/step/`` is the reward module of an untrusted copy of PutAppleBowl (under a
scratch root, so it is statically checked and runs under the guard), made with ``gym.make``. The late payloads
misbehave only when the first action component is exactly 1.0 (which the probe's random actions never send), so the
test chooses the step.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch

from gendex_envs.errors import GenDexError, RewardModuleError
from gendex_envs.registry import REFERENCE_TASKS, register_tasks, resolve_task, unregister_tasks
from gendex_envs.reward_checks import RESERVED_INFO_KEYS, RewardOutputError, check_evaluate, check_reward
from gendex_envs.reward_module import load_reward_module
from gendex_envs.success import Judge
from gendex_envs.task_version import NAMESPACE, TaskLayout

PAYLOADS = Path(__file__).resolve().parent.parent / "data" / "hostile_r2" / "step"
SOURCE = "PutAppleBowl"


@pytest.fixture(scope="module")
def hostile(tmp_path_factory):
    """``hostile("nan_reward_late")``: an untrusted copy of PutAppleBowl whose reward module is that payload,
    registered; returns its env id. Ids are removed at the end of the module."""
    root = tmp_path_factory.mktemp("hostile_tasks")
    source = resolve_task(SOURCE)
    made: list[str] = []

    def copy(payload: str) -> str:
        name = "Hostile" + "".join(w.capitalize() for w in payload.split("_"))
        folder = root / name / "v0"
        source.copy_to(folder)
        layout = TaskLayout(folder)
        layout.spec.write_text(layout.spec.read_text().replace(f"name: {SOURCE}\n", f"name: {name}\n"))
        layout.reward.write_text((PAYLOADS / f"{payload}.py").read_text())
        made.extend(register_tasks([root], override=True))
        return f"{NAMESPACE}/{name}-v0"

    yield copy
    unregister_tasks(sorted(set(made)))


def _make(env_id: str):
    return gym.make(env_id, control_mode="pd_joint_delta_pos")


def _still(env) -> np.ndarray:
    return np.zeros(env.action_space.shape, dtype=np.float32)


def _trigger(env) -> np.ndarray:
    action = _still(env)
    action[0] = 1.0
    return action


def _assert_names_module(exc: RewardOutputError, env_id: str, fn: str, step: int) -> None:
    text = str(exc)
    assert isinstance(exc, RewardModuleError) and isinstance(exc, GenDexError)
    assert exc.fn == fn and exc.step == step, (exc.fn, exc.step, text)
    name = env_id.split("/")[1].rsplit("-", 1)[0]
    assert f"{name}/v0/reward.py" in text and f", {fn} returned" in text, text
    assert (f"at step {step}" if step else "right after reset (step 0)") in text, text


@pytest.mark.parametrize(("payload", "kind"), [("nan_reward_late", "NaN"), ("inf_reward_late", "inf")])
def test_non_finite_reward_after_the_probe_is_stopped(hostile, payload, kind):
    env_id = hostile(payload)
    env = _make(env_id)
    try:
        env.reset(seed=0)
        for _ in range(24):  # past the probe's 20 steps, every reward finite
            _, reward, *_ = env.step(_still(env))
            assert math.isfinite(reward)
        with pytest.raises(RewardOutputError) as caught:
            env.step(_trigger(env))  # step 25
    finally:
        env.close()
    _assert_names_module(caught.value, env_id, "compute_dense_reward", 25)
    assert f"non-finite values ({kind}) in the reward for env(s) [0]" in str(caught.value)
    assert "values must be finite and within" in str(caught.value)


def test_reward_of_wrong_shape_is_stopped(hostile):
    env_id = hostile("wrong_shape_reward")
    env = _make(env_id)
    try:
        env.reset(seed=0)
        env.step(_still(env))
        with pytest.raises(RewardOutputError) as caught:
            env.step(_trigger(env))
    finally:
        env.close()
    _assert_names_module(caught.value, env_id, "compute_dense_reward", 2)
    assert "tensor of shape (1, 1)" in str(caught.value) and "expected shape (1,)" in str(caught.value)


@pytest.mark.parametrize("key", ["is_success", "success", "elapsed_steps"])
def test_evaluate_may_not_return_success_or_bookkeeping_keys(hostile, key):
    env_id = hostile(f"evaluate_{key}")
    with pytest.raises(RewardOutputError) as caught:  # the env's first reset already evaluates
        env = _make(env_id)
        try:
            env.reset(seed=0)
            env.step(_still(env))
        finally:
            env.close()
    _assert_names_module(caught.value, env_id, "evaluate", 0)
    assert f"the key {key!r}" in str(caught.value) or f"returned {key!r}" in str(caught.value)
    assert key in RESERVED_INFO_KEYS


def test_evaluate_diagnostics_must_be_finite(hostile):
    env_id = hostile("evaluate_inf_diagnostic")
    with pytest.raises(RewardOutputError) as caught:
        _make(env_id).close()
    _assert_names_module(caught.value, env_id, "evaluate", 0)
    assert "non-finite values (inf) in 'apple_height'" in str(caught.value)


@pytest.mark.parametrize("key", ["palm_pose", "qpos"])
def test_obs_extra_may_not_replace_the_env_or_agent_observations(hostile, key):
    env_id = hostile(f"obs_{key}")
    with pytest.raises(RewardOutputError) as caught:
        _make(env_id).close()
    _assert_names_module(caught.value, env_id, "_get_obs_extra", 0)
    assert f"returned the key {key!r}, which would replace the env's own observation" in str(caught.value)
    assert "'tip_pos'" in str(caught.value)  # the message lists the names taken


def test_reward_code_cannot_see_the_step_count(hostile):
    """The payload returns 1 while it sees ``info["elapsed_steps"]`` <= 20, NaN after, and 0 when it cannot see it."""
    env = _make(hostile("reward_reads_elapsed_steps"))
    try:
        env.reset(seed=0)
        rewards = []
        for _ in range(25):
            _, reward, _, _, info = env.step(_still(env))
            rewards.append(float(reward))
        assert int(info["elapsed_steps"]) == 25  # the user still gets the step count; only reward code does not
    finally:
        env.close()
    assert rewards == [0.0] * 25


def test_checks_hold_for_a_reward_module_built_elsewhere(task_version):
    """A RewardModule whose functions are not load_reward_module's (a worker process's, the probe's) is checked where
    the judge and the env take its outputs."""
    module = load_reward_module(task_version(SOURCE).files.reward)
    rogue = type(module)(path=Path("/elsewhere/reward.py"), evaluate=lambda env: {"is_success": env.spec_success()},
                         compute_dense_reward=lambda env, obs, action, info: torch.full((env.num_envs,), math.nan),
                         get_obs_extra=None, reward_max=1.0)
    env = _make(f"{NAMESPACE}/{SOURCE}-v1")
    try:
        base = env.unwrapped
        spec = base.task_spec
        base.judge = Judge.of_task(spec, rogue)
        with pytest.raises(RewardOutputError, match=r"^reward module /elsewhere/reward.py: .*'is_success'"):
            env.reset(seed=0)
        base.judge = Judge.of_task(spec, type(module)(module.path, module.evaluate, rogue.compute_dense_reward,
                                                      module.get_obs_extra, module.reward_max))
        env.reset(seed=0)
        with pytest.raises(RewardOutputError, match=r"at step 1, compute_dense_reward returned non-finite"):
            env.step(_still(env))
    finally:
        env.close()


def test_the_checks_are_the_rules_and_nothing_more():
    n, cpu = 2, torch.device("cpu")
    ok = {"fail": torch.zeros(n, dtype=torch.bool), "d": torch.ones(n, 3), "k": torch.ones(n, dtype=torch.int64)}
    assert check_evaluate(ok, n, cpu).keys() == ok.keys()
    assert torch.equal(check_reward(torch.full((n,), -1e9), n, cpu), torch.full((n,), -1e9))
    for bad, reason in [
        ({"fail": torch.zeros(n)}, "expected a torch.bool tensor"),
        ({"d": torch.ones(n + 1)}, "leading dimension num_envs=2"),
        ({"d": torch.ones(n, 2000)}, "at most 1024 values per env"),
        ({"TimeLimit.truncated": torch.ones(n)}, "names matching"),
        ({f"k{i}": torch.ones(n) for i in range(65)}, "at most 64 are allowed"),
        ({"d": torch.tensor([0.0, 2e9])}, "values beyond ±1e+09 in 'd' for env(s) [1]"),
        ([("fail", torch.zeros(n, dtype=torch.bool))], "expected a dict"),
    ]:
        with pytest.raises(RewardOutputError, match=re.escape(reason)):
            check_evaluate(bad, n, cpu, path="m.py", step=3)


# ---------------------------------------------------------------------------------------------- committed modules
SAMPLE = (*REFERENCE_TASKS, "RotateTennisBall", "StackBlocks", "TurnFaucet")


@pytest.mark.parametrize("name", SAMPLE)
def test_committed_modules_pass_the_checks_on_every_step(task_version, name):
    """The task module and each stage module of a sample of committed tasks, 10 random steps each, every output
    checked (the env raises on the first broken rule)."""
    version = task_version(name)
    env = gym.make(version.env_id)
    try:
        base = env.unwrapped
        spec = base.task_spec
        judges = [base.judge, *(version.judge(s.name) for s in spec.stages if version.has_stage_reward(s.name))]
        assert len(judges) > 1 or name != "PutAppleBowl"
        rng = np.random.default_rng(0)
        for judge in judges:
            base.judge = judge
            env.reset(seed=1)
            for _ in range(10):
                _, reward, *_ = env.step(rng.uniform(env.action_space.low, env.action_space.high).astype(np.float32))
                assert math.isfinite(reward)
    finally:
        env.close()
