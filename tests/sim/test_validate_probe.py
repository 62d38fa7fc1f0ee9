"""Reward probe: candidate modules run in a child process against the real task env; every bad output is named.

The bad modules share one child process (the first test's fixture); the tests that kill the child (time limit,
crash) share another.
"""

from __future__ import annotations

import dataclasses
import json
import re
import time
from pathlib import Path

import pytest

from gendex_envs.registry import resolve_task
from generator.errors import RewardProbeError, UnsafeCodeError
from generator.steps.validate import (
    ProbeReport,
    ValidationReport,
    probe_task,
    validate_reward_module,
    validate_task,
)

TASK = resolve_task("GenDex/PutAppleBowl-v0").root
SHIPPED = resolve_task("GenDex/PutAppleBowl-v0").files.reward
SHIPPED_NAME = resolve_task("GenDex/PutAppleBowl-v0").files.relative(SHIPPED)

HEAD = "import torch\n\n"
EVALUATE = (
    "def evaluate(env):\n"
    "    s = env.spec_success()\n"
    "    return {'fail': torch.zeros_like(s)}\n"
)
REWARD = (
    "def compute_dense_reward(env, obs, action, info):\n"
    "    return torch.zeros(env.num_envs, device=env.device)\n"
)

BAD_MODULES = {
    "shape_n1": HEAD + EVALUATE + (
        "def compute_dense_reward(env, obs, action, info):\n"
        "    return torch.zeros(env.num_envs, 1, device=env.device)\n"),
    "python_float": HEAD + EVALUATE + (
        "def compute_dense_reward(env, obs, action, info):\n"
        "    return 0.5\n"),
    "nan": HEAD + EVALUATE + (
        "def compute_dense_reward(env, obs, action, info):\n"
        "    d = torch.linalg.norm(env.palm_pose.p - env.palm_pose.p, dim=-1)\n"
        "    return d / d\n"),
    "no_fail": HEAD + (
        "def evaluate(env):\n"
        "    return {'inside': env.spec_success()}\n") + REWARD,
    "grants_success": HEAD + (
        "def evaluate(env):\n"
        "    s = torch.ones(env.num_envs, dtype=torch.bool, device=env.device)\n"
        "    return {'success': s, 'fail': ~s}\n") + REWARD,
    "raises": HEAD + (
        "def evaluate(env):\n"
        "    apple = env.obj_pose('apple').p\n"
        "    s = apple[:, 0] > 1.0\n"
        "    return {'fail': s & (apple[:, 2] / 0.0 > [1][3])}\n") + REWARD,
    "float_flags": HEAD + (
        "def evaluate(env):\n"
        "    s = env.spec_success().float()\n"
        "    return {'fail': torch.zeros_like(s)}\n") + REWARD,
    "import_fails": HEAD + "SCALE = 1 / 0\n\n" + EVALUATE + REWARD,
    "bad_obs": HEAD + EVALUATE + REWARD + (
        "def _get_obs_extra(env, info):\n"
        "    return {'tips': env.tip_positions}\n"),
    "memory": HEAD + EVALUATE + (
        "def compute_dense_reward(env, obs, action, info):\n"
        "    big = torch.ones(2**31, device=env.device)\n"
        "    return big[: env.num_envs]\n"),
}


def write_modules(folder: Path, sources: dict[str, str]) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, source in sources.items():
        path = folder / f"{name}.py"
        path.write_text(source, encoding="utf-8")
        paths.append(path)
    return paths


@pytest.fixture(scope="module")
def batch(tmp_path_factory) -> ValidationReport:
    """The shipped task reward module plus every bad module, validated in one child process."""
    folder = tmp_path_factory.mktemp("candidates")
    modules = [SHIPPED, *write_modules(folder, BAD_MODULES)]
    return validate_task(TASK, modules, steps=8, timeout_s=30, memory_limit_mb=1024)


def outcome(report: ValidationReport, name: str):
    (found,) = [m for m in report.modules if m.module in (name, f"{name}.py")]
    return found


def probe_error(report: ValidationReport, name: str) -> str:
    o = outcome(report, name)
    assert not o.ok and o.failed_at == "probe" and o.error_type == "RewardProbeError", o
    assert o.error.startswith(f"{name}.py: "), o.error
    return o.error


def test_shipped_reward_passes_static_check_and_probe(batch):
    o = outcome(batch, SHIPPED_NAME)
    assert o.ok, o.error
    r = o.probe
    assert isinstance(r, ProbeReport) and r.steps == 8 and r.num_envs == 1
    assert 0.0 <= r.reward_min <= r.reward_mean <= r.reward_max <= 5.0
    assert r.obs_extra == {"apple_to_bowl": [3]}
    assert 0.0 <= r.success_rate <= 1.0 and r.wall_s > 0


def test_report_is_json_and_lists_every_module(batch):
    assert not batch.ok and len(batch.modules) == 1 + len(BAD_MODULES)
    data = json.loads(batch.to_json())
    assert data == json.loads(json.dumps(dataclasses.asdict(batch)))
    assert data["modules"][0]["module"] == SHIPPED_NAME
    with pytest.raises(RewardProbeError, match=r"^shape_n1\.py: "):
        batch.raise_first()


def test_reward_of_shape_n_by_1_is_rejected(batch):
    message = probe_error(batch, "shape_n1")
    assert "at step 1, compute_dense_reward returned a torch.float32 tensor of shape (1, 1)" in message
    assert "expected shape (1,)" in message and ".squeeze(-1)" in message


def test_python_float_reward_is_rejected(batch):
    message = probe_error(batch, "python_float")
    assert "compute_dense_reward returned a Python float (0.5); expected a float tensor of shape (1,)" in message


def test_nan_reward_is_rejected(batch):
    message = probe_error(batch, "nan")
    assert "compute_dense_reward returned non-finite values (NaN) in the reward for env(s) [0]" in message


def test_evaluate_without_fail_is_rejected(batch):
    message = probe_error(batch, "no_fail")
    assert "right after reset (step 0), evaluate returned keys ['inside'] without 'fail'" in message


def test_reward_code_cannot_grant_success(batch):
    message = probe_error(batch, "grants_success")
    assert "evaluate returned 'success', but success is declared in the task spec" in message


def test_exception_in_evaluate_names_type_and_line(batch):
    message = probe_error(batch, "raises")
    assert "right after reset (step 0), evaluate raised IndexError: list index out of range at line 6" in message
    assert "[1][3]" in message  # the offending source line is quoted


def test_float_flags_are_rejected(batch):
    message = probe_error(batch, "float_flags")
    assert "returned 'fail' as a torch.float32 tensor of shape (1,) on cpu; expected a torch.bool tensor" in \
        message


def test_import_error_names_the_line(batch):
    message = probe_error(batch, "import_fails")
    assert "importing it failed: ZeroDivisionError: division by zero at line 3" in message


def test_observation_with_three_dims_is_rejected(batch):
    message = probe_error(batch, "bad_obs")
    assert "_get_obs_extra returned 'tips' as a torch.float32 tensor of shape (1, 5, 3)" in message
    assert "at most 2 dimensions" in message


def test_memory_blowup_fails_inside_the_reward_code(batch):
    message = probe_error(batch, "memory")
    assert "compute_dense_reward raised RuntimeError" in message and "allocate memory" in message
    assert "at line 7 (`big = torch.ones(2**31, device=env.device)`)" in message


def test_killed_children_are_replaced_and_report_the_cause(tmp_path, monkeypatch):
    """Time limit, audit hook and crash, without the static check that would stop the first two before running,
    and with all code trusted: the runtime guard's restricted builtins would refuse `open` and `faulthandler`
    before the child's own fences (time limit, its audit hook, crash report) are reached."""
    from gendex_envs.guard import TRUST_ENV

    monkeypatch.setenv(TRUST_ENV, "1")
    loop, audit, crash, good = write_modules(tmp_path, {
        "loop": HEAD + EVALUATE + (
            "def compute_dense_reward(env, obs, action, info):\n"
            "    while True:\n"
            "        pass\n"),
        "audit": HEAD + EVALUATE + (
            "def compute_dense_reward(env, obs, action, info):\n"
            "    with open('/etc/hostname') as f:\n"
            "        f.read()\n"
            "    return torch.zeros(env.num_envs)\n"),
        "crash": "import faulthandler\n" + HEAD + EVALUATE + (
            "def compute_dense_reward(env, obs, action, info):\n"
            "    faulthandler._sigsegv()\n"),
        "good": HEAD + EVALUATE + REWARD,
    })
    t0 = time.monotonic()
    report = validate_task(TASK, [loop, audit, crash, good], steps=3, timeout_s=8, check_static=False)
    assert time.monotonic() - t0 < 60
    assert [m.failed_at for m in report.modules] == ["probe", "probe", "probe", None]
    results = [RewardProbeError(m.error) if m.error else m.probe for m in report.modules]
    loop_err, audit_err, crash_err, good_report = results
    assert isinstance(loop_err, RewardProbeError)
    assert re.search(r"^loop\.py: compute_dense_reward did not finish within the time limit of 8 s at step 1 "
                     r"\(infinite loop\?\); it was stopped at line [78] \(`(while True:|pass)`\)",
                     str(loop_err)), loop_err
    assert isinstance(audit_err, RewardProbeError)
    assert "compute_dense_reward tried to reach outside the simulator (open('/etc/hostname'" in str(audit_err)
    assert isinstance(crash_err, RewardProbeError)
    assert "crash.py: the probe process was killed by SIGSEGV while running compute_dense_reward at step 1" in \
        str(crash_err)
    assert "at line 8 (`faulthandler._sigsegv()`)" in str(crash_err)
    assert isinstance(good_report, ProbeReport) and good_report.steps == 3
    assert report.modules[3].ok and not report.ok


def test_probe_task_raises_for_the_first_bad_module(tmp_path):
    (nan,) = write_modules(tmp_path, {"nan": BAD_MODULES["nan"]})
    with pytest.raises(RewardProbeError, match=r"^nan\.py: at step 1, compute_dense_reward returned non-finite"):
        probe_task(TASK, [SHIPPED, nan], steps=3, timeout_s=30)


def test_probe_task_runs_the_static_check_first(tmp_path):
    (bad,) = write_modules(tmp_path, {"unsafe": "import os\n" + EVALUATE + REWARD})
    t0 = time.monotonic()
    with pytest.raises(UnsafeCodeError, match=r"^unsafe\.py was rejected"):
        probe_task(TASK, [SHIPPED, bad])
    with pytest.raises(UnsafeCodeError, match=r"line 1: `import os` is not allowed"):
        validate_reward_module(TASK, bad)
    assert time.monotonic() - t0 < 5  # no simulator was started
