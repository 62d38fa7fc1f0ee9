"""The second wall (issue 43, round two): untrusted reward modules run in a confined worker process
(gendex_envs.sandbox), so that a hole in the first wall (the static check and the restricted builtins) still
reaches no file, process, network or other process, and every call is bounded in time and memory.

The hostile modules in ``tests/data/hostile_r2/sandbox/`` are loaded as untrusted code with the first wall taken
away: ``static_check=False``, Python's ordinary builtins in the worker (``FULL_BUILTINS_FOR_TESTS``) and, for the
in-process path, the guard's restricted builtins and audit hook switched off. Each must leave no marker, reach no
listener, kill no process and end in a typed error within the limits; the env keeps working afterwards. With
``GENDEX_IN_PROCESS_GUARD=1`` (untrusted code in this process, as before the sandbox) these tests fail.
"""

from __future__ import annotations

import builtins
import os
import signal
import socket
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest
import torch

from gendex_envs import guard
from gendex_envs.errors import GenDexError, RewardModuleError
from gendex_envs.registry import REFERENCE_TASKS, resolve_task
from gendex_envs.reward_module import load_reward_module

REPO = Path(__file__).resolve().parents[2]
PAYLOADS = REPO / "tests" / "data" / "hostile_r2" / "sandbox"
CALL_LIMIT_S = 2.0


def _sandbox_host():
    from gendex_envs.sandbox import host  # absent before the sandbox: the test fails there

    return host


@pytest.fixture(scope="module")
def env(reward_env):
    return reward_env


@pytest.fixture
def first_wall_down(monkeypatch):
    """As if the static check and the in-process guard had a hole: ordinary builtins, no audit hook."""
    monkeypatch.setattr(guard, "restricted_builtins", lambda: dict(vars(builtins)))
    monkeypatch.setattr(guard, "untrust", lambda folder: None)
    monkeypatch.setattr("gendex_envs.sandbox.host.FULL_BUILTINS_FOR_TESTS", True, raising=False)
    monkeypatch.setenv("GENDEX_SANDBOX_TIMEOUT_S", str(CALL_LIMIT_S))


def _module(tmp_path: Path, name: str, **values) -> Path:
    text = (PAYLOADS / f"{name}.py").read_text()
    for key, value in values.items():
        text = text.replace("{" + key + "}", str(value))
    folder = tmp_path / "tasks" / name.title().replace("_", "") / "v0"
    folder.mkdir(parents=True)
    path = folder / "reward.py"
    path.write_text(text)
    return path


def _evaluate(path: Path, env, limit_s: float = 60.0):
    """Load ``path`` as untrusted code without the static check and call its ``evaluate``; returns (error or None,
    seconds). A call still running after ``limit_s`` is reported as such (and left behind in a daemon thread)."""
    box: dict = {}

    def run():
        try:
            box["module"] = load_reward_module(path, trusted=False, static_check=False)
            box["value"] = box["module"].evaluate(env)
        except BaseException as exc:
            box["error"] = exc

    start = time.monotonic()
    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(limit_s)
    assert not thread.is_alive(), f"{path.name}'s evaluate was still running after {limit_s} s"
    _evaluate.last_module = box.get("module")  # keeps the module, and so its worker, alive for the test's checks
    return box.get("error"), time.monotonic() - start


def _children(pid: int) -> list[int]:
    out = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                out.append(int(entry.name))
    return out


def _worker_pid() -> int:
    """The pid of the worker the last loaded module runs in (held alive by that module)."""
    return _sandbox_host().shared_worker().proc.pid


def _healthy(env, tmp_path: Path) -> None:
    """After an attack, an honest untrusted module still loads and runs against the same env."""
    honest = tmp_path / "honest" / "Honest" / "v0" / "reward.py"
    honest.parent.mkdir(parents=True)
    honest.write_text(resolve_task("PutAppleBowl").files.reward.read_text())
    module = load_reward_module(honest, trusted=False)
    info = module.evaluate(env)
    assert info["fail"].shape == (env.num_envs,)


# ---------------------------------------------------------------------------------------------- files
@pytest.mark.parametrize("name", ["write_file", "read_passwd", "read_secret"])
def test_files_are_out_of_reach(env, tmp_path, first_wall_down, name):
    marker, secret = tmp_path / "marker", tmp_path / "secret.txt"
    secret.write_text("the user's own data")
    error, _ = _evaluate(_module(tmp_path, name, marker=marker, secret=secret), env)
    assert isinstance(error, RewardModuleError) and "PermissionError" in str(error), error
    assert str(tmp_path) in str(error)  # it names the module
    assert not marker.exists()
    _healthy(env, tmp_path)


# ---------------------------------------------------------------------------------------------- processes
@pytest.mark.parametrize("name", ["os_system", "subprocess_run", "os_fork"])
def test_no_process_is_started(env, tmp_path, first_wall_down, name):
    marker = tmp_path / "marker"
    before = set(_children(os.getpid()))
    error, _ = _evaluate(_module(tmp_path, name, marker=marker), env)
    time.sleep(0.3)
    assert not marker.exists()
    worker = _worker_pid()
    assert _children(worker) == []  # nothing started by the worker is left (or was ever started)
    assert set(_children(os.getpid())) - before <= {worker}
    if name != "os_system":  # glibc's system() reports a refused spawn as status 127, not as an error
        assert isinstance(error, RewardModuleError) and "PermissionError" in str(error), error
    _healthy(env, tmp_path)


def test_no_signal_reaches_another_process(env, tmp_path, first_wall_down):
    victim = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)"])
    try:
        error, _ = _evaluate(_module(tmp_path, "kill_parent", victim=victim.pid), env)
        time.sleep(0.3)
        assert victim.poll() is None, "the victim was killed"
        assert isinstance(error, RewardModuleError) and "PermissionError" in str(error), error
    finally:
        victim.kill()
        victim.wait()


def test_no_connection_is_made(env, tmp_path, first_wall_down):
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(1)
    listener.settimeout(0.5)
    try:
        error, _ = _evaluate(_module(tmp_path, "socket_connect", port=listener.getsockname()[1]), env)
        with pytest.raises(TimeoutError):
            listener.accept()
        assert isinstance(error, RewardModuleError) and "PermissionError" in str(error), error
    finally:
        listener.close()


# ---------------------------------------------------------------------------------------------- limits
def test_memory_is_capped(env, tmp_path, first_wall_down):
    from gendex_envs.errors import RewardSandboxError

    error, _ = _evaluate(_module(tmp_path, "allocate_20gb"), env)
    assert isinstance(error, RewardSandboxError) and "memory" in str(error) and "GENDEX_SANDBOX_MEMORY_MB" in \
        str(error), error
    _healthy(env, tmp_path)


@pytest.mark.parametrize("name", ["loop_forever", "sleep_forever"])
def test_a_call_is_bounded_in_time_and_the_worker_is_stopped(env, tmp_path, first_wall_down, monkeypatch, name):
    from gendex_envs.errors import RewardTimeoutError

    workers, load = [], load_reward_module

    def load_and_note(*args, **kwargs):
        module = load(*args, **kwargs)
        workers.append(_worker_pid())
        return module

    monkeypatch.setitem(globals(), "load_reward_module", load_and_note)
    error, elapsed = _evaluate(_module(tmp_path, name), env, limit_s=30)
    monkeypatch.undo()
    assert isinstance(error, RewardTimeoutError), error
    assert CALL_LIMIT_S <= elapsed < CALL_LIMIT_S + 10, elapsed
    worker = workers[0]
    text = str(error)
    assert "evaluate" in text and str(tmp_path) in text and "GENDEX_SANDBOX_TIMEOUT_S" in text and \
        f"{CALL_LIMIT_S:g} s" in text
    assert not Path(f"/proc/{worker}").exists(), "the worker that ran past the limit is still there"
    _healthy(env, tmp_path)  # a new worker serves the next module


# ---------------------------------------------------------------------------------------------- the channel
FAKE_WORKER = '''
import json, os, struct, sys
def send(header, payload=b""):
    text = json.dumps(header).encode()
    os.write(1, struct.pack("<IQ", len(text), len(payload)) + text + payload)
def read():
    n, m = struct.unpack("<IQ", os.read(0, 12))
    data = b""
    while len(data) < n + m:
        data += os.read(0, n + m - len(data))
    return json.loads(data[:n])
MODE = {mode!r}
if MODE == "unconfined":
    send({{"op": "unconfined", "msg": "Landlock is not available (Linux >= 5.13 with Landlock enabled is needed)"}})
    sys.exit(3)
send({{"op": "ready", "walls": []}})
while True:
    msg = read()
    if msg["op"] == "load":
        send({{"op": "loaded", "functions": ["compute_dense_reward", "evaluate"], "reward_max": 1.0}})
    elif MODE == "huge":
        os.write(1, struct.pack("<IQ", 10, 1 << 40))
    elif MODE == "bad_dtype":
        send({{"op": "ret", "value": {{"$t": 0}}, "tensors": [["object", [1], 0]]}}, b"x" * 8)
    elif MODE == "short":
        send({{"op": "ret", "value": {{"$t": 0}}, "tensors": [["float32", [1000], 0]]}}, b"x" * 8)
    elif MODE == "pickle":
        send({{"op": "ret", "value": {{"py/object": "os.system"}}}})
    elif MODE == "die":
        os._exit(9)
'''


@pytest.mark.parametrize("mode,reason", [("huge", "at most"), ("bad_dtype", "dtype"), ("short", "outside the payload"),
                                         ("pickle", "untagged"), ("die", "exited with status 9")])
def test_malformed_or_dead_workers_give_typed_errors(env, tmp_path, monkeypatch, mode, reason):
    from gendex_envs.errors import RewardSandboxError

    host = _sandbox_host()
    fake = tmp_path / "fake_worker.py"
    fake.write_text(FAKE_WORKER.format(mode=mode))
    monkeypatch.setattr(host, "WORKER", fake)
    monkeypatch.setattr(host, "_shared", None)
    module = load_reward_module(_module(tmp_path, "write_file", marker=tmp_path / "m"), trusted=False,
                                static_check=False)
    with pytest.raises(RewardSandboxError) as caught:
        module.evaluate(env)
    assert reason in str(caught.value) and str(tmp_path) in str(caught.value), str(caught.value)


def test_a_system_that_cannot_confine_refuses_untrusted_code(tmp_path, monkeypatch):
    from gendex_envs.errors import RewardSandboxError

    host = _sandbox_host()
    fake = tmp_path / "fake_worker.py"
    fake.write_text(FAKE_WORKER.format(mode="unconfined"))
    monkeypatch.setattr(host, "WORKER", fake)
    monkeypatch.setattr(host, "_shared", None)
    path = tmp_path / "tasks" / "Honest" / "v0" / "reward.py"
    path.parent.mkdir(parents=True)
    path.write_text(resolve_task("PutAppleBowl").files.reward.read_text())
    with pytest.raises(RewardSandboxError) as caught:
        load_reward_module(path, trusted=False)
    text = str(caught.value)
    assert "Landlock is not available" in text and "trust_remote_code=True" in text and \
        "GENDEX_IN_PROCESS_GUARD=1" in text
    monkeypatch.setenv("GENDEX_IN_PROCESS_GUARD", "1")  # the named opt-out: the first wall alone, in this process
    module = load_reward_module(path, trusted=False)
    assert module.evaluate.__wrapped__.__module__.startswith("gendex_reward_")


# ---------------------------------------------------------------------------------------------- lifetime
def test_the_worker_dies_with_its_parent(tmp_path):
    script = textwrap.dedent(f'''
        import sys, time
        from gendex_envs.reward_module import load_reward_module
        from gendex_envs.sandbox import host
        module = load_reward_module({str(resolve_task("PutAppleBowl").files.reward)!r}, trusted=False)
        print("WORKER", host.shared_worker().proc.pid, flush=True)
        time.sleep(600)
    ''')
    parent = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True, cwd=REPO)
    try:
        line = parent.stdout.readline()
        assert line.startswith("WORKER"), line
        worker = int(line.split()[1])
        assert Path(f"/proc/{worker}").exists()
    finally:
        parent.send_signal(signal.SIGKILL)
        parent.wait()
    deadline = time.monotonic() + 10
    while Path(f"/proc/{worker}").exists() and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not Path(f"/proc/{worker}").exists(), "the worker outlived its parent"


# ---------------------------------------------------------------------------------------------- same results
@pytest.mark.parametrize("name", REFERENCE_TASKS)
def test_an_untrusted_copy_gives_the_trusted_rewards_success_and_observations(task_copy, name):
    from gendex_envs.task_env import TaskEnv

    def rollout(version):
        e = TaskEnv(task=version, obs_mode="state", control_mode="pd_joint_delta_pos", render_backend="none")
        try:
            obs, _ = e.reset(seed=5)
            rng = torch.Generator().manual_seed(1)
            out = [(obs.clone(),)]
            for _ in range(15):
                action = torch.rand(e.action_space.shape, generator=rng) * 2 - 1
                obs, reward, terminated, truncated, info = e.step(action)
                out.append((obs.clone(), reward.clone(), info["success"].clone(), info["fail"].clone()))
            return out, e.reward
        finally:
            e.close()

    trusted, trusted_module = rollout(resolve_task(name))
    copy = task_copy(name, as_name=f"Sandboxed{name}", register=False)
    untrusted, untrusted_module = rollout(copy)
    assert not hasattr(untrusted_module.evaluate, "__wrapped__")  # it ran in the worker, not in this process
    assert hasattr(trusted_module.evaluate, "__wrapped__")
    assert len(trusted) == len(untrusted) == 16
    for a, b in zip(trusted, untrusted, strict=True):
        for x, y in zip(a, b, strict=True):
            assert x.dtype == y.dtype and torch.equal(x, y)


def test_errors_of_the_real_view_are_raised_as_they_are(env, tmp_path):
    path = tmp_path / "tasks" / "Unknown" / "v0" / "reward.py"
    path.parent.mkdir(parents=True)
    path.write_text(textwrap.dedent('''
        import torch


        def evaluate(env):
            return {"h": env.obj_height("no_such_object")}


        def compute_dense_reward(env, obs, action, info):
            return torch.zeros(env.num_envs, device=env.device)
    '''))
    module = load_reward_module(path, trusted=False)
    with pytest.raises(GenDexError) as sandboxed:
        module.evaluate(env)
    with pytest.raises(GenDexError) as direct:
        env.obj_height("no_such_object")
    assert type(sandboxed.value) is type(direct.value) and str(sandboxed.value) == str(direct.value)


def test_the_wire_format_round_trips_every_allowed_dtype_and_refuses_others():
    from gendex_envs.sandbox import protocol

    value = {"f32": torch.randn(2, 3), "bf16": torch.randn(3).to(torch.bfloat16), "b": torch.tensor([True, False]),
             "i64": torch.arange(5), "u8": torch.arange(3, dtype=torch.uint8), "empty": torch.zeros(0, 3),
             "scalar": torch.tensor(2.5, dtype=torch.float64), "nan": float("nan"), "nested": [1, "x", None, (2.5,)],
             "strided": torch.arange(12.0).reshape(3, 4)[:, 1]}
    read, write = os.pipe()
    try:
        tensors: list = []
        protocol.write_frame(write, {"op": "ret", "value": protocol.encode(value, tensors)}, tensors)
        out = protocol.read_frame(read)["value"]
    finally:
        os.close(read)
        os.close(write)
    for key, expected in value.items():
        if isinstance(expected, torch.Tensor):
            assert out[key].dtype == expected.dtype and torch.equal(out[key], expected), key
    assert out["nested"] == [1, "x", None, [2.5]] and out["nan"] != out["nan"]
    for bad in (torch.zeros(2, dtype=torch.complex64), object(), {1: torch.zeros(1)}):
        with pytest.raises(protocol.ProtocolError):
            protocol.encode(bad, [])
