"""The reward probe's child runs model-written candidates behind the kernel's walls too (issue 43, untrusted task
folders): Landlock, seccomp, no new privileges, no capabilities, like the sandbox's worker
(``gendex_envs/sandbox/confine.py``).

The candidates are loaded with the first wall taken away (:data:`generator.steps.probe.FIRST_WALL_DOWN_FOR_TESTS`:
no static check, Python's ordinary builtins, neither the runtime guard's audit hook nor the probe's own), as in
``tests/security/test_sandbox.py``. Each tries to write a file outside the probe's folder, read a user's file,
connect to a local listener, start a process, raise its own memory limit, or kill or limit another process; none
may leave a marker, read the secret, reach the listener or touch the other process, and each must end in a typed
failure naming it, while an honest module probed in the same child still passes. A system that cannot confine the
child refuses to probe, naming what is missing and the opt-out. Before the child raised these walls, every attack
here succeeded.
"""

from __future__ import annotations

import logging
import os
import resource
import socket
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from gendex_envs.errors import RewardSandboxError
from gendex_envs.registry import resolve_task
from generator.errors import RewardProbeError
from generator.steps import probe
from generator.steps.probe import ProbeReport, probe_modules

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Landlock and seccomp are Linux's")

TASK = resolve_task("GenDex/PutAppleBowl-v1")
SECRET = "the user's own data"
API_KEY = "sk-ant-probe-test-0123456789"
"""Stands for the model's API key in the parent's environment."""
OK = "return {'fail': torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}"
REWARD = (
    "def compute_dense_reward(env, obs, action, info):\n"
    "    return torch.zeros(env.num_envs, device=env.device)\n"
)


def _candidate(attack: str) -> str:
    """A module whose ``evaluate`` (called at the reset) runs ``attack`` first."""
    body = textwrap.indent(textwrap.dedent(attack).strip() + "\n" + OK, "    ")
    return f"import torch\n\n\ndef evaluate(env):\n{body}\n\n\n{REWARD}"


def _attacks(marks: Path, secret: Path, beside: Path, port: int, victim: int) -> dict[str, str]:
    return {
        "write_file": f"open({str(marks / 'write_file')!r}, 'w').write('pwned')",
        "read_secret": f"""
            text = open({str(secret)!r}).read()
            raise RuntimeError('read: ' + text)
        """,
        "read_beside": f"""
            text = open({str(beside)!r}).read()
            raise RuntimeError('read: ' + text)
        """,
        "connect": f"""
            import socket
            socket.create_connection(('127.0.0.1', {port}), timeout=2).sendall(b'pwned')
        """,
        # glibc's system() reports a refused spawn as status 127, not as an error: the candidate says so itself
        "os_system": f"""
            import os
            status = os.system('touch {marks / 'os_system'}')
            if status != 0:
                raise OSError(f'os.system ran nothing (status {{status}})')
        """,
        "subprocess_run": f"""
            import subprocess
            subprocess.run(['/bin/sh', '-c', 'touch {marks / 'subprocess_run'}'])
        """,
        "os_fork": f"""
            import os
            pid = os.fork()
            if pid == 0:
                open({str(marks / 'os_fork')!r}, 'w').write('pwned')
                os._exit(0)
            os.waitpid(pid, 0)
        """,
        # the child's RLIMIT_DATA soft limit is its memory budget, its hard limit is higher
        "raise_limit": """
            import resource
            hard = resource.getrlimit(resource.RLIMIT_DATA)[1]
            resource.setrlimit(resource.RLIMIT_DATA, (hard, hard))
        """,
        "limit_victim": f"""
            import resource
            resource.prlimit({victim}, resource.RLIMIT_NOFILE, (3, 3))
        """,
        "kill_victim": f"""
            import os
            os.kill({victim}, 9)
        """,
        "read_environment": """
            import os
            raise RuntimeError('environment: ' + repr(sorted(os.environ.items())))
        """,
    }


EXPECTED = {"os_system": "OSError: os.system ran nothing", "raise_limit": "ValueError: not allowed to raise"}
"""What each refused attack raises when it is not ``PermissionError`` (glibc's system() reports status 127;
CPython's setrlimit turns EPERM into this ValueError)."""


class _Records(logging.Handler):
    def __init__(self):
        super().__init__(logging.DEBUG)
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())


def _probe(modules: list[Path], **kwargs) -> tuple[list, list[str]]:
    """``probe_modules`` on the committed task with 2 steps; returns (results, the parent's log messages)."""
    records = _Records()
    logger = logging.getLogger(probe.__name__)
    level = logger.level
    logger.addHandler(records)
    logger.setLevel(logging.DEBUG)
    try:
        results = probe_modules(TASK.root, modules, steps=2, timeout_s=60, seed=0, num_envs=1,
                                sim_backend="physx_cpu", memory_limit_mb=2048, startup_timeout_s=300,
                                stop_on_error=False, check_static=False, **kwargs)
    finally:
        logger.removeHandler(records)
        logger.setLevel(level)
    return results, records.messages


@pytest.fixture(scope="module")
def hostile(tmp_path_factory):
    """Every attack and then the committed task's own reward module, in one child, with the first wall down."""
    root = tmp_path_factory.mktemp("probe_confinement")
    marks, candidates = root / "marks", root / "candidates"
    marks.mkdir()
    candidates.mkdir()
    secret = root / "secret.txt"
    secret.write_text(SECRET)
    beside = candidates / "notes.txt"  # beside the candidates: only the module files themselves are readable
    beside.write_text(SECRET)
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(4)
    listener.settimeout(0.5)
    victim = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(300)"])
    victim_files = resource.prlimit(victim.pid, resource.RLIMIT_NOFILE)
    attacks = _attacks(marks, secret, beside, listener.getsockname()[1], victim.pid)
    paths = []
    for name, attack in attacks.items():
        path = candidates / f"{name}.py"
        path.write_text(_candidate(attack), encoding="utf-8")
        paths.append(path)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(probe, "FIRST_WALL_DOWN_FOR_TESTS", True, raising=False)
        mp.delenv("GENDEX_IN_PROCESS_GUARD", raising=False)
        mp.delenv("GENDEX_TRUST_REMOTE_CODE", raising=False)
        mp.setenv("ANTHROPIC_API_KEY", API_KEY)
        results, messages = _probe([*paths, TASK.files.reward])
    try:
        victim_alive = victim.poll() is None
        victim_limited = resource.prlimit(victim.pid, resource.RLIMIT_NOFILE) != victim_files if victim_alive \
            else None
        connections = []
        while True:
            try:
                connections.append(listener.accept()[0])
            except TimeoutError:
                break
        for c in connections:
            c.close()
    finally:
        listener.close()
        victim.kill()
        victim.wait()
    return {"results": dict(zip([*attacks, "honest"], results, strict=True)), "marks": marks,
            "connections": len(connections), "messages": messages, "victim_alive": victim_alive,
            "victim_limited": victim_limited}


@pytest.mark.parametrize("name", ["write_file", "read_secret", "read_beside", "connect", "os_system",
                                  "subprocess_run", "os_fork", "raise_limit", "limit_victim", "kill_victim"])
def test_a_candidate_past_the_first_wall_reaches_nothing(hostile, name):
    result = hostile["results"][name]
    assert isinstance(result, RewardProbeError), f"{name}: the probe reported {result!r}"
    text = str(result)
    assert text.startswith(f"{name}.py: right after reset (step 0), evaluate raised "), text
    assert EXPECTED.get(name, "PermissionError") in text, text
    assert SECRET not in text
    assert list(hostile["marks"].iterdir()) == []


def test_the_childs_environment_holds_no_credentials(hostile):
    """What a candidate can read of its environment goes back to the model in its error: no key is there."""
    text = str(hostile["results"]["read_environment"])
    assert "environment: [" in text and "'PATH'" in text, text  # it did read its environment
    assert API_KEY not in text and "ANTHROPIC_API_KEY" not in text


def test_no_connection_reached_the_listener(hostile):
    assert hostile["connections"] == 0


def test_another_process_was_neither_killed_nor_limited(hostile):
    assert hostile["victim_alive"] and hostile["victim_limited"] is False


def test_an_honest_module_still_passes_behind_the_walls(hostile):
    report = hostile["results"]["honest"]
    assert isinstance(report, ProbeReport) and report.steps == 2, report


def test_the_walls_raised_are_logged(hostile):
    (line,) = [m for m in hostile["messages"] if "walls:" in m]
    for wall in ("landlock: files read-only", "no write", "seccomp: no exec, fork, sockets", "no new privileges"):
        assert wall in line, line
    if os.geteuid() == 0:
        assert "capabilities: none" in line, line


@pytest.fixture
def no_seccomp(tmp_path, monkeypatch):
    """The child finds a ``pyseccomp`` that cannot load libseccomp (first on its ``PYTHONPATH``), as on a system
    without it; this process keeps its own."""
    fake = tmp_path / "fake_site"
    fake.mkdir()
    (fake / "pyseccomp.py").write_text("raise ImportError('libseccomp.so.2 was not found (test)')\n")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(fake), *filter(None, [os.environ.get("PYTHONPATH")])]))
    monkeypatch.delenv("GENDEX_IN_PROCESS_GUARD", raising=False)
    monkeypatch.delenv("GENDEX_TRUST_REMOTE_CODE", raising=False)


def test_a_system_that_cannot_confine_the_child_refuses_to_probe(no_seccomp):
    with pytest.raises(RewardSandboxError) as caught:
        _probe([TASK.files.reward])
    text = str(caught.value)
    assert "seccomp is not available" in text and "libseccomp" in text, text
    assert "GENDEX_IN_PROCESS_GUARD=1" in text, text


def test_the_opt_out_probes_under_the_first_wall_alone(no_seccomp, monkeypatch):
    monkeypatch.setenv("GENDEX_IN_PROCESS_GUARD", "1")
    (report,), messages = _probe([TASK.files.reward])
    assert isinstance(report, ProbeReport) and report.steps == 2, report
    assert any("unconfined" in m and "GENDEX_IN_PROCESS_GUARD=1" in m for m in messages), messages
