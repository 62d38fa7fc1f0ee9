"""Red team, round two (issue 43): hostile inputs written after the fixes, in the issue's classes, against the new
code (the strict reader, the allow-list, the sandbox's parent, the per-step checks, the registry, promote, dataset
pull, saved tensors).

Each test asserts the safe outcome: a typed :class:`~gendex_envs.errors.GenDexError` (or a contained, harmless
result), no marker file, nothing written outside where it may write, and an end within a few seconds. Payloads are
in ``tests/data/hostile_r2/redteam/`` or built here from a committed task. Every escape this round found is closed;
an escape found later and not yet closed is recorded as ``xfail(strict=True)`` naming the code that should close it.
"""

from __future__ import annotations

import io
import json
import os
import re
import shutil
import subprocess
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest
import torch

from gendex_envs import registry
from gendex_envs.code_check import check_reward_source
from gendex_envs.code_check.source import decode_reward_source
from gendex_envs.errors import GenDexError, PolicyError, StageError, UnsafeCodeError
from gendex_envs.reward_checks import check_evaluate, check_obs_extra
from gendex_envs.reward_module import load_reward_module
from gendex_envs.task_version import Artifacts, TaskLayout, TaskVersion, derive_version

REPO = Path(__file__).resolve().parents[2]
PAYLOADS = REPO / "tests" / "data" / "hostile_r2" / "redteam"
LOADING = PAYLOADS / "loading"
CALL_LIMIT_S = 2.0


def _untrusted(tmp_path: Path, text: str, name: str = "RedTeam") -> Path:
    """``text`` as the task reward module of an untrusted folder ``tmp_path/downloads/<name>/v0``."""
    path = tmp_path / "downloads" / name / "v0" / "reward.py"
    path.parent.mkdir(parents=True)
    path.write_text(text)
    return path


@pytest.fixture(scope="module", autouse=True)
def env():
    """A committed task's env (its own, trusted reward module); hostile modules are called against it. Built before
    any test loads an untrusted module: the runtime guard's audit hook, installed then for the rest of the process,
    makes building a scene four times slower."""
    from gendex_envs.registry import resolve_task
    from gendex_envs.task_env import TaskEnv

    e = TaskEnv(task=resolve_task("PutAppleBowl"), obs_mode="state", control_mode="pd_joint_delta_pos",
                render_backend="none")
    e.reset(seed=0)
    yield e
    e.close()


# ------------------------------------------------------------------------------------ what runs is what was checked
SPLIT_ESCAPES = sorted(LOADING.glob("utf7_cookie_behind_*_on_line1.py"))
"""A utf-7 cookie on the importer's line 2, behind \\v \\f \\x1c-\\x1e on line 1 (where str.splitlines() ends a line and
the importer does not): the reader looks at the lines as every cutter cuts them."""
REFUSED_ALREADY = sorted(p for p in LOADING.glob("*.py") if not p.stem.startswith("utf7_cookie_behind_")
                         and p.stem != "nul_byte_in_code")


def test_the_loading_corpus_is_there():
    assert len(SPLIT_ESCAPES) == 5 and len(REFUSED_ALREADY) >= 7


@pytest.mark.parametrize("path", SPLIT_ESCAPES + REFUSED_ALREADY, ids=lambda p: getattr(p, "stem", str(p)))
def test_an_encoding_the_importer_would_use_is_refused(path):
    """Python's importer decodes each of these by a declaration or BOM that is not UTF-8 (``tokenize`` agrees); the
    strict reader must refuse them all, not only those whose declaration it happens to find."""
    with pytest.raises(UnsafeCodeError, match="only UTF-8 is allowed"):
        decode_reward_source(path.read_bytes(), path.name)


@pytest.mark.parametrize("path", sorted(LOADING.glob("*.py")), ids=lambda p: p.stem)
def test_hidden_encoded_code_never_runs_trusted_or_not(path, tmp_path):
    """Whatever the reader decides, the hidden utf-7 line (a comment to a UTF-8 reader, ``open(marker)`` to the
    importer) never runs, from a trusted folder (no static check) or an untrusted one."""
    marker = tmp_path / "marker"
    for trusted in (True, False):
        module = tmp_path / ("t" if trusted else "u") / "Enc" / "v0" / "reward.py"
        module.parent.mkdir(parents=True)
        module.write_bytes(path.read_bytes().replace(b"{marker}", str(marker).encode()))
        try:
            load_reward_module(module, trusted=trusted)
        except GenDexError:
            pass
        assert not marker.exists(), f"{path.name}: hidden code ran (trusted={trusted})"
        assert not (module.parent / "__pycache__").exists()


def test_a_nul_byte_is_a_typed_error_not_a_crash(tmp_path):
    module = _untrusted(tmp_path, (LOADING / "nul_byte_in_code.py").read_text())
    with pytest.raises(GenDexError, match="reward.py"):
        load_reward_module(module, trusted=True)


# ---------------------------------------------------------------------------------------------- trust by path
def test_a_reward_module_linked_into_the_trusted_root_is_not_trusted(tmp_path, monkeypatch):
    trusted_root = tmp_path / "repo" / "generated_tasks"
    monkeypatch.setattr(registry, "REPO_TASKS_DIR", trusted_root)
    marker = tmp_path / "marker"
    target = trusted_root / "Promoted" / "v1" / "policies" / "lift" / "progress.csv"
    target.parent.mkdir(parents=True)
    target.write_text((PAYLOADS / "trust" / "linked_module_target.py").read_text().replace("{marker}", str(marker)))
    link = tmp_path / "downloads" / "Linked" / "v0" / "reward.py"
    link.parent.mkdir(parents=True)
    link.symlink_to(target)
    try:
        load_reward_module(link)
    except GenDexError:
        pass
    assert not marker.exists(), "a module linked from an untrusted folder ran as trusted code"


# ---------------------------------------------------------------------------------------------- the allow-list
def test_uninitialised_memory_cannot_carry_state_across_calls(env, tmp_path, monkeypatch):
    monkeypatch.setenv("GENDEX_SANDBOX_TIMEOUT_S", str(CALL_LIMIT_S))
    module = _untrusted(tmp_path, (PAYLOADS / "state" / "tensor_ctor_counter.py").read_text())
    try:
        loaded = load_reward_module(module, trusted=False)
    except GenDexError:
        return  # refused before it ran: safe
    counts = []
    for _ in range(6):
        try:
            counts.append(float(loaded.evaluate(env)["count"][0]))
        except GenDexError:
            return
    assert counts == [0.0] * 6, f"the module counted its calls through freed memory: {counts}"


@pytest.mark.parametrize("call", ["torch.Tensor(4)", "torch.Tensor(torch.Size([2, 2]))", "torch.Tensor(2, 3)"])
def test_the_legacy_tensor_constructor_is_refused(call):
    src = (f"import torch\n\n\ndef evaluate(env):\n    x = {call}\n    return {{\"fail\": x.sum() > 1}}\n\n\n"
           "def compute_dense_reward(env, obs, action, info):\n    return torch.zeros(env.num_envs)\n")
    with pytest.raises(UnsafeCodeError):
        check_reward_source(src, "legacy.py")


# ---------------------------------------------------------------------------------------------- the sandbox's parent
def _env_reads(monkeypatch) -> list:
    """Counts the real env's ``hand_forces`` computations (what the sandbox's parent does for the worker)."""
    from gendex_envs.task_env import TaskEnv

    calls: list = []
    real = TaskEnv.hand_forces

    def counted(self, *args, **kwargs):
        calls.append(args)
        return real(self, *args, **kwargs)

    monkeypatch.setattr(TaskEnv, "hand_forces", counted)
    return calls


def test_a_flood_of_distinct_env_reads_ends_each_call_within_the_limit(env, tmp_path, monkeypatch):
    """1500 distinct (meaningless) ``hand_forces`` parts a call, varied by the robot's state: the sandbox's parent
    files every key a call asked for and recomputes them before each later call (outside the call's own limit) until
    the frame passes the wire format's tensor bound and the worker is stopped. Each call must still end, returned or
    with a typed error, within the limit plus a worker restart."""
    monkeypatch.setenv("GENDEX_SANDBOX_TIMEOUT_S", str(CALL_LIMIT_S))
    module = _untrusted(tmp_path, (PAYLOADS / "sandbox" / "hand_forces_key_flood.py").read_text())
    loaded = load_reward_module(module, trusted=False)
    reads = _env_reads(monkeypatch)
    for _ in range(3):
        reads.clear()
        start = time.monotonic()
        try:
            loaded.evaluate(env)
        except GenDexError:
            pass
        assert time.monotonic() - start < 2 * CALL_LIMIT_S + 8, f"a call took {time.monotonic() - start:.1f} s"
        assert len(reads) <= 20_000
        env.step(torch.as_tensor(env.action_space.sample()))


def _honest_still_runs(env, tmp_path: Path) -> None:
    honest = _untrusted(tmp_path, (REPO / "generated_tasks" / "PutAppleBowl" / "v1" / "reward.py").read_text(),
                        name="Honest")
    info = load_reward_module(honest, trusted=False).evaluate(env)
    assert set(info) >= {"fail"}


def test_a_2mb_object_name_asked_of_the_parent_is_a_typed_error(env, tmp_path, monkeypatch):
    """``env.obj_pose(name)`` with a 2 MB name: the worker's request frame passes the header bound."""
    monkeypatch.setenv("GENDEX_SANDBOX_TIMEOUT_S", str(CALL_LIMIT_S))
    loaded = load_reward_module(_untrusted(tmp_path, (PAYLOADS / "sandbox" / "member_hostile_arguments.py")
                                           .read_text()), trusted=False)
    start = time.monotonic()
    with pytest.raises(GenDexError, match="reward.py"):
        loaded.evaluate(env)
    assert time.monotonic() - start < CALL_LIMIT_S
    _honest_still_runs(env, tmp_path)


def test_an_overlong_part_name_is_a_gendex_error(env, tmp_path, monkeypatch):
    monkeypatch.setenv("GENDEX_SANDBOX_TIMEOUT_S", str(CALL_LIMIT_S))
    loaded = load_reward_module(_untrusted(tmp_path, (PAYLOADS / "sandbox" / "member_hostile_arguments.py")
                                           .read_text()), trusted=False)
    with pytest.raises(GenDexError):  # a bare TypeError from the parent's key check before the sandbox's d23184c
        loaded.compute_dense_reward(env, None, None, {})


@pytest.mark.parametrize("path", sorted((PAYLOADS / "resources").glob("*.py")), ids=lambda p: p.stem)
def test_unbounded_work_through_allowed_names_is_a_typed_error_within_the_limit(env, tmp_path, monkeypatch, path):
    """Memory (2**62 zeros, a 2**31 expand made contiguous, one_hot of 1e11), CPU (a sum over
    2**40 broadcast elements) and recursion, through allow-listed names only."""
    monkeypatch.setenv("GENDEX_SANDBOX_TIMEOUT_S", str(CALL_LIMIT_S))
    loaded = load_reward_module(_untrusted(tmp_path, path.read_text()), trusted=False)
    start = time.monotonic()
    with pytest.raises(GenDexError, match="reward.py"):
        loaded.evaluate(env)
    assert time.monotonic() - start < CALL_LIMIT_S + 3
    _honest_still_runs(env, tmp_path)


@pytest.fixture
def first_wall_down(monkeypatch):
    """As if the static check and the restricted builtins had a hole: the worker runs the module with Python's
    ordinary builtins (only the OS confinement is left)."""
    import builtins

    from gendex_envs import guard

    monkeypatch.setattr(guard, "restricted_builtins", lambda: dict(vars(builtins)))
    monkeypatch.setattr(guard, "untrust", lambda folder: None)
    monkeypatch.setattr("gendex_envs.sandbox.host.FULL_BUILTINS_FOR_TESTS", True)
    monkeypatch.setenv("GENDEX_SANDBOX_TIMEOUT_S", str(CALL_LIMIT_S))


@pytest.fixture
def victim():
    """Another process of this user, holding a secret in its environment."""
    import subprocess
    import sys

    proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)"],
                            env={**os.environ, "GENDEX_REDTEAM_TOKEN": "hf_redteam_secret_token"})
    yield proc
    proc.kill()
    proc.wait()


def _first_wall_down_evaluate(env, tmp_path: Path, name: str, **values):
    text = (PAYLOADS / "sandbox" / f"{name}.py").read_text()
    for key, value in values.items():
        text = text.replace("{" + key + "}", str(value))
    loaded = load_reward_module(_untrusted(tmp_path, text), trusted=False, static_check=False)
    try:
        loaded.evaluate(env)
    except GenDexError as exc:
        return exc
    return None


def test_the_worker_cannot_renice_or_pin_another_process(env, tmp_path, first_wall_down, victim):
    before = os.getpriority(os.PRIO_PROCESS, victim.pid), os.sched_getaffinity(victim.pid)
    error = _first_wall_down_evaluate(env, tmp_path, "renice_and_pin_victim", victim=victim.pid)
    after = os.getpriority(os.PRIO_PROCESS, victim.pid), os.sched_getaffinity(victim.pid)
    assert after == before, f"the worker changed another process's scheduling: {before} -> {after}"
    assert error is not None


def test_no_signal_by_rt_sigqueueinfo_reaches_another_process(env, tmp_path, first_wall_down, victim):
    error = _first_wall_down_evaluate(env, tmp_path, "sigqueue_victim", victim=victim.pid)
    time.sleep(0.2)
    assert victim.poll() is None, "the victim was signalled"
    assert error is not None and "PermissionError" in str(error), error


def test_seccomp_alone_stops_rt_sigqueueinfo_to_another_process(tmp_path, victim):
    """Landlock's signal scope needs ABI 6 (Linux 6.12); the sandbox also runs on older kernels (any ABI from 1),
    where only the seccomp filter stands between the worker and its parent's pid."""
    import subprocess
    import sys

    confine = REPO / "gendex_envs" / "sandbox" / "confine.py"
    payload = (PAYLOADS / "sandbox" / "sigqueue_victim.py").read_text().replace("{victim}", str(victim.pid))
    script = (f"import importlib.util, types\n"
              f"spec = importlib.util.spec_from_file_location('confine', {str(confine)!r})\n"
              "confine = importlib.util.module_from_spec(spec); spec.loader.exec_module(confine)\n"
              "confine.seccomp(confine.load_seccomp())\n"
              "ns = {}\n"
              f"exec({payload!r}.replace('import torch', 'torch = None'), ns)\n"
              "try:\n    ns['evaluate'](None)\nexcept PermissionError as exc:\n    print('refused', exc)\n")
    done = subprocess.run([sys.executable, "-I", "-c", script], capture_output=True, text=True, timeout=60)
    time.sleep(0.2)
    assert victim.poll() is None, f"seccomp let rt_sigqueueinfo through: {done.stdout} {done.stderr[-500:]}"
    assert "refused" in done.stdout, done.stderr[-2000:]


def test_the_worker_reads_no_other_process_the_repository_or_home(env, tmp_path, first_wall_down, victim):
    error = _first_wall_down_evaluate(env, tmp_path, "read_proc_and_repo", victim=victim.pid, repo=REPO)
    assert error is not None
    assert "LEAKED" not in str(error) and "hf_redteam_secret_token" not in str(error), str(error)[:2000]
    assert "every read was refused" in str(error)


# ---------------------------------------------------------------------------------------------- per-step outputs
@pytest.mark.parametrize("key", ["Success", "success ", "s\u0443ccess", "is_success\n", "_final_info",
                                 "TimeLimit.truncated", "episode", "final_info", "terminal_observation", "reward"])
def test_evaluate_keys_other_tools_read_are_refused_in_every_spelling(key):
    info = {"fail": torch.zeros(1, dtype=torch.bool), key: torch.ones(1, dtype=torch.bool)}
    with pytest.raises(GenDexError):
        check_evaluate(info, 1, "cpu", path="r.py", step=30)


@pytest.mark.parametrize("key", ["palm_pose", "apple_pose", "tip_pos", "goal_pos", "agent", "extra", "qpos",
                                 "Palm_pose", "palm_pose\n", "controller"])
def test_task_observations_cannot_take_the_envs_names_in_any_spelling(key):
    taken = {"palm_pose": None, "tip_pos": None, "apple_pose": None, "bowl_pose": None, "goal_pos": None}
    with pytest.raises(GenDexError):
        check_obs_extra({key: torch.zeros(1, 3)}, 1, "cpu", taken, path="r.py", step=30)


@pytest.mark.parametrize("dtype, value", [(torch.int64, 2**62), (torch.int64, -2**63), (torch.int32, 2**31 - 1)])
def test_an_integer_task_observation_is_bounded_like_a_float_one(dtype, value):
    with pytest.raises(GenDexError):
        check_obs_extra({"count": torch.full((1, 3), value, dtype=dtype)}, 1, "cpu", {}, path="r.py", step=30)


def test_a_float_fail_is_refused():
    with pytest.raises(GenDexError):
        check_evaluate({"fail": torch.ones(1)}, 1, "cpu", path="r.py", step=30)


def _hostile_copy(task_copy, as_name: str, edit) -> TaskVersion:
    """An untrusted copy of PutAppleBowl (not registered) whose text files ``edit`` rewrote."""
    version = task_copy("PutAppleBowl", as_name=as_name, register=False)
    for path in version.root.rglob("*"):
        if path.suffix in (".py", ".yaml"):
            path.write_text(edit(path, path.read_text()))
    return TaskVersion.at(version.root)


def test_reward_max_cannot_make_the_normalized_reward_infinite(task_copy):
    from gendex_envs.task_env import TaskEnv

    version = _hostile_copy(task_copy, "RedRewardMax", lambda p, t: re.sub(r"(?m)^REWARD_MAX = .*$",
                                                                           "REWARD_MAX = 1e-300", t))
    try:
        e = TaskEnv(task=version, obs_mode="state", control_mode="pd_joint_delta_pos", render_backend="none")
        assert e.reward_mode == "normalized_dense"
        e.reset(seed=0)
        rewards = [e.step(torch.as_tensor(e.action_space.sample()))[1] for _ in range(2)]
    except GenDexError:
        return
    assert all(bool(torch.isfinite(r).all()) for r in rewards), rewards


def test_an_object_name_cannot_replace_the_palm_observation(task_copy):
    from gendex_envs.task_env import TaskEnv

    version = _hostile_copy(task_copy, "RedPalm", lambda p, t: t.replace("apple", "palm")
                            .replace("asset: palm", "asset: apple"))
    try:
        e = TaskEnv(task=version, obs_mode="state_dict", control_mode="pd_joint_delta_pos", render_backend="none")
        obs, _ = e.reset(seed=0)
    except GenDexError:
        return
    assert torch.equal(obs["extra"]["palm_pose"], e.palm_pose.raw_pose), "palm_pose is not the palm's pose"


def test_start_states_of_the_wrong_width_are_a_typed_error(tmp_path):
    from gendex_envs.registry import resolve_task
    from gendex_envs.start_states import StartStates
    from gendex_envs.task_env import TaskEnv

    unit = np.tile(np.array([1, 0, 0, 0], np.float32), (2, 1))
    states = StartStates(stage="reach_apple", state=np.zeros((2, 5), np.float32),
                         obj_reset_pos={"apple": np.zeros((2, 3), np.float32), "bowl": np.zeros((2, 3), np.float32)},
                         obj_reset_quat={"apple": unit, "bowl": unit}).save(tmp_path / "narrow.npz")
    with pytest.raises(GenDexError):
        e = TaskEnv(task=resolve_task("PutAppleBowl"), obs_mode="state", control_mode="pd_joint_delta_pos",
                    render_backend="none", start_states=states)
        e.reset(seed=0)


# ---------------------------------------------------------------------------------------------- identity
def test_a_higher_version_on_the_tasks_path_does_not_take_a_committed_name(tmp_path):
    from gendex_envs.registry import REPO_TASKS_DIR, register_tasks, resolve_task, unregister_tasks

    root = tmp_path / "tasks"
    shutil.copytree(REPO_TASKS_DIR / "PutAppleBowl" / "v1", root / "PutAppleBowl" / "v9",
                    ignore=shutil.ignore_patterns("__pycache__"))
    made = register_tasks([root])
    try:
        resolved = resolve_task("PutAppleBowl").root.resolve()
    finally:
        unregister_tasks(made)
    assert resolved.is_relative_to(REPO_TASKS_DIR.resolve()), f"the bare name now resolves to {resolved}"


# ---------------------------------------------------------------------------------------------- forged results
def _board_with(tmp_path: Path, edit) -> tuple[str, Path]:
    """A copy of a committed reference-suite result, changed by ``edit(dict)`` (or replaced by the text it returns)."""
    from gendex.eval.leaderboard import LEADERBOARD_DIR

    suite = "gendex-ref-v1"
    honest = sorted((LEADERBOARD_DIR / suite).glob("*.json"))[0]
    data = json.loads(honest.read_text())
    out = edit(data)
    (tmp_path / "board" / suite).mkdir(parents=True)
    (tmp_path / "board" / suite / "forged.json").write_text(out if isinstance(out, str) else json.dumps(data))
    return suite, tmp_path / "board"


def _drop_task(data: dict) -> None:
    per_task = data["eval_info"]["per_task"]
    hard = min(per_task, key=lambda t: per_task[t]["pc_success"])
    del per_task[hard]  # a result on the easy tasks only, its aggregate left as it was
    data["eval_info"]["per_episode"] = [e for e in data["eval_info"]["per_episode"] if e.get("task_id") != hard]


def _raise_aggregate(data: dict) -> None:
    data["eval_info"]["aggregated"]["pc_success"] = 100.0  # per-task numbers left as they were


def _zero_episodes(data: dict) -> None:
    task = next(iter(data["eval_info"]["per_task"]))
    data["eval_info"]["per_task"][task].update(episodes=0, successes=0, pc_success=0.0)


@pytest.mark.parametrize("edit", [
    pytest.param(lambda d: "[" * 100_000 + "]" * 100_000, id="nested_100k"),
    pytest.param(lambda d: '{"method": ' + "9" * 5000 + "}", id="int_5000_digits"),
    pytest.param(_zero_episodes, id="zero_episodes"),
    pytest.param(_raise_aggregate, id="aggregate_not_the_tasks"),
    pytest.param(_drop_task, id="hardest_task_left_out"),
])
def test_the_board_refuses_a_forged_or_malformed_result_with_a_typed_error(tmp_path, edit):
    from gendex.eval.leaderboard import load_entries

    suite, root = _board_with(tmp_path, edit)
    with pytest.raises(GenDexError):
        load_entries(suite, root)


def test_the_board_still_loads_an_honest_result(tmp_path):
    from gendex.eval.leaderboard import load_entries

    suite, root = _board_with(tmp_path, lambda d: None)
    assert len(load_entries(suite, root)) == 1


# ---------------------------------------------------------------------------------------------- promote
def _versions(source: TaskVersion) -> list[str]:
    return sorted(p.name for p in source.root.parent.iterdir())


def _run_with(tmp_path: Path, stage: str, make) -> Path:
    """A training run folder with an honest policy record and zip for ``stage``, then changed by ``make``."""
    run = tmp_path / "run"
    layout = TaskLayout(run)
    layout.policies.mkdir(parents=True)
    layout.policy(stage).write_bytes(b"PK\x05\x06" + bytes(18))  # an empty zip: promote copies, never loads
    layout.policy_record(stage).write_text("{}")
    make(layout, tmp_path)
    return run


def _secret(tmp_path: Path) -> Path:
    secret = tmp_path / "home" / ".ssh" / "id_rsa"
    secret.parent.mkdir(parents=True, exist_ok=True)
    secret.write_text("-----BEGIN OPENSSH PRIVATE KEY----- red team")
    return secret


def _link_policy(layout: TaskLayout, tmp_path: Path) -> None:
    layout.policy(STAGE).unlink()
    layout.policy(STAGE).symlink_to(_secret(tmp_path))


def _link_record(layout: TaskLayout, tmp_path: Path) -> None:
    layout.policy_record(STAGE).unlink()
    layout.policy_record(STAGE).symlink_to(_secret(tmp_path))


def _link_curve(layout: TaskLayout, tmp_path: Path) -> None:
    layout.policy_curves(STAGE).mkdir(parents=True)
    (layout.policy_curves(STAGE) / "progress.csv").symlink_to(_secret(tmp_path))


def _link_policies_folder(layout: TaskLayout, tmp_path: Path) -> None:
    elsewhere = tmp_path / "elsewhere"
    shutil.move(layout.policies, elsewhere)
    shutil.copy(_secret(tmp_path), elsewhere / f"{STAGE}.zip")
    layout.policies.symlink_to(elsewhere, target_is_directory=True)


def _fifo_start_states(layout: TaskLayout, tmp_path: Path) -> None:
    layout.start_states_dir.mkdir()
    os.mkfifo(layout.start_states(STAGE))


def _linked_start_states(layout: TaskLayout, tmp_path: Path) -> None:
    layout.start_states_dir.mkdir()
    layout.start_states(STAGE).symlink_to(_secret(tmp_path))


def _nan_start_states(layout: TaskLayout, tmp_path: Path) -> None:
    layout.start_states_dir.mkdir()
    shutil.copy(REPO / "tests" / "data" / "hostile_r2" / "files" / "start_states_nan.npz", layout.start_states(STAGE))


def _odd_stage_name(layout: TaskLayout, tmp_path: Path) -> None:
    layout.policy(STAGE).rename(layout.policies / "...zip")
    layout.policy_record(STAGE).rename(layout.policies / "...json")
    (layout.policies / "..").joinpath("progress.csv").write_text("x")


STAGE = "reach_apple"


@pytest.mark.parametrize("make", [_link_policy, _link_record, _link_curve, _link_policies_folder, _fifo_start_states,
                                  _linked_start_states, _nan_start_states, _odd_stage_name], ids=lambda f: f.__name__)
def test_promote_copies_nothing_but_the_runs_own_regular_files(task_copy, tmp_path, make):
    """``gendex promote`` of a hostile run folder: a link would copy ``~/.ssh/id_rsa`` (or ``/dev/zero``, forever)
    into the published task version; a FIFO would stop the copy. Each is a StageError and publishes nothing."""
    source = task_copy("PutAppleBowl", as_name="RedPromote", register=False)
    assert STAGE in {s.name for s in source.spec.stages}
    run = _run_with(tmp_path, STAGE, make)
    before = _versions(source)
    start = time.monotonic()
    with pytest.raises(StageError):
        derive_version(source, [Artifacts(run)], {"command": "red team"})
    assert time.monotonic() - start < 10
    assert _versions(source) == before, "a version was published"
    leaked = [p for p in source.root.parent.rglob("*") if p.is_file() and not p.is_symlink()
              and b"PRIVATE KEY" in p.read_bytes()]
    assert leaked == []


def test_promote_still_publishes_an_honest_run(task_copy, tmp_path):
    source = task_copy("PutAppleBowl", as_name="RedPromoteOk", register=False)
    run = _run_with(tmp_path, STAGE, lambda layout, tmp: None)
    new = derive_version(source, [Artifacts(run)], {"command": "red team"})
    assert new.version == source.version + 1
    assert TaskLayout(new.root).policy_record(STAGE).read_text() == "{}"


# ---------------------------------------------------------------------------------------------- dataset pull
class _Download:
    """A remote whose download is a folder prepared here (as a Hub snapshot would be)."""

    def __init__(self, folder: Path):
        self.folder = folder

    def pull(self, repo_id: str, out: Path) -> Path:
        return self.folder


def test_a_deeply_nested_download_is_a_typed_error_and_leaves_nothing(tmp_path):
    from gendex.data.datasets import BUILD_RECORD, DatasetError, pull

    download = tmp_path / "download"
    download.mkdir()
    (download / BUILD_RECORD).write_text(json.dumps({"tasks": [{"task": "GenDex/Deep-v0"}]}))
    here = os.getcwd()
    os.chdir(download)
    try:
        for _ in range(500):  # 500 levels: copytree's recursion raised a bare RecursionError
            os.mkdir("a")
            os.chdir("a")
        Path("data.parquet").write_text("rows")
    finally:
        os.chdir(here)
    work = tmp_path / "work"
    work.mkdir()
    start = time.monotonic()
    try:
        with pytest.raises(DatasetError, match="MAX_DOWNLOAD_DEPTH"):
            pull("org/deep", work / "out", _Download(download))
        assert time.monotonic() - start < 5
        assert list(work.iterdir()) == []
    finally:  # rm, not shutil.rmtree: its recursion would pass the audit hook's stack walk 500 levels deep
        subprocess.run(["rm", "-rf", str(download / "a")], check=True)


# ---------------------------------------------------------------------------------------------- saved tensors
def _stride_bomb(n: int) -> torch.Tensor:
    """A 4-byte storage recorded with shape [n] and stride 0: ``torch.load(weights_only=True)`` accepts it."""
    return torch.zeros(1).expand(n)


@pytest.mark.parametrize("n", [2**40, 2**31])
def test_a_policy_weight_that_is_a_strided_view_of_one_value_is_refused_at_once(tmp_path, n):
    """2**40 raised a bare RuntimeError (4 TB asked of the allocator); 2**31 took 37 s and 2 GB (``isfinite``)."""
    from gendex.solve.policy import read_policy_weights
    from gendex_envs.task_version import TaskVersion

    honest = TaskVersion.at(REPO / "generated_tasks" / "RotateTennisBall" / "v0").policy("rotate_ball").model
    buf = io.BytesIO()
    torch.save({"mlp_extractor.policy_net.0.weight": _stride_bomb(n)}, buf)
    path = tmp_path / "bomb.zip"
    with zipfile.ZipFile(honest) as zi, zipfile.ZipFile(path, "w") as zo:
        for info in zi.infolist():
            zo.writestr(info, buf.getvalue() if info.filename == "policy.pth" else zi.read(info))
    assert len(buf.getvalue()) < 10_000  # the whole policy.pth
    start = time.monotonic()
    with pytest.raises(PolicyError, match="strided view"):
        read_policy_weights(path)
    assert time.monotonic() - start < 2


def _toy_bc(tmp_path: Path, weights: dict | None = None, **changes) -> Path:
    """A tiny BC checkpoint of format 2 (``torch.save``, as ``save_checkpoint`` writes it), with ``changes``."""
    info = {"config": {"chunk": 2, "hidden": 8, "layers": 2, "steps": 1, "batch": 1, "lr": 1e-3,
                       "weight_decay": 0.0, "obs_noise": 0.0, "ensemble_decay": 0.1, "seed": 0},
            "names": {"observation.state": ["s0"]}, "task_id": "GenDex/Toy-v0",
            "env_kwargs": {"control_mode": "pd_joint_pos"}, "training_seeds": [1], "demos": 1, "frames": 10,
            "dataset": "toy", "final_loss": 0.5, "seconds": 1.0, **changes}
    norm = {k: torch.as_tensor(np.ones(2), dtype=torch.float32) for k in ("x_mean", "x_std", "a_mean", "a_std")}
    path = tmp_path / "bc.pt"
    torch.save({"format": 2, "model": weights if weights is not None else {"0.weight": torch.zeros(2, 2)},
                **norm, **info}, path)
    return path


def _cycle() -> list:
    loop: list = []
    loop.append(loop)
    return loop


def _shared_along_2_to_the_60_paths() -> list:
    node: list = ["leaf"]
    for _ in range(60):
        node = [node, node]
    return node


def _nested(depth: int) -> list:
    node: list = []
    for _ in range(depth):
        node = [node]
    return node


@pytest.mark.timeout(30)
@pytest.mark.parametrize("value", [_cycle, _shared_along_2_to_the_60_paths, lambda: _nested(200)],
                         ids=["list_holding_itself", "shared_2_to_the_60_paths", "nested_200"])
def test_bc_checkpoint_metadata_that_is_no_json_tree_is_refused_at_once(tmp_path, value):
    """A pickle's memo makes a list that holds itself: the metadata check walked it forever (``gendex eval --policy
    bc:PATH`` hung), and one list shared along 2**60 paths would take as long."""
    from gendex.imitation.bc import load_checkpoint

    path = _toy_bc(tmp_path, names={"observation.state": value()})
    start = time.monotonic()
    with pytest.raises(PolicyError, match="JSON values"):
        load_checkpoint(path)
    assert time.monotonic() - start < 2


def test_a_bc_checkpoint_weight_that_is_a_strided_view_is_refused_at_once(tmp_path):
    from gendex.imitation.bc import load_checkpoint

    path = _toy_bc(tmp_path, weights={"0.weight": _stride_bomb(2**40)})
    start = time.monotonic()
    with pytest.raises(PolicyError, match="strided view"):
        load_checkpoint(path)
    assert time.monotonic() - start < 2


@pytest.mark.parametrize("raw", [["hand_forces", "apple", "p123", None], ["hand_forces", "apple", None, "j1"],
                                 ["entity.pose", "apple", None, "any joint"],
                                 ["entity.linear_velocity", "a", "x", None]])
def test_the_parent_refuses_member_arguments_the_real_view_would_ignore(raw):
    """Arguments the real view ignores (a part that is not 'handle', a joint without the handle) would each make a
    new key the parent computes and prefetches: refused before the view is asked."""
    from gendex_envs.sandbox.host import _key

    with pytest.raises(TypeError, match="part is None"):
        _key(raw)
    assert _key(["hand_forces", "apple", None, None]) == ("hand_forces", "apple", None, None)
