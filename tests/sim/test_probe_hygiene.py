"""Process hygiene of the reward probe: nothing it starts or writes outlives its parent, and a hung child ends itself.

A parent Python process runs :func:`generator.steps.probe.probe_task` on a copy of a committed task with a module
that loops forever while it is imported; once the child is inside that module the test kills the parent and then
looks for every process the parent had started (recorded from ``/proc`` beforehand) and for ``gendex_probe_*``
folders in the parent's ``TMPDIR``. Linux only (``/proc``).
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from generator.errors import RewardProbeError
from generator.steps import probe_child
from generator.steps.probe import probe_task

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")

ROOT = Path(__file__).resolve().parents[2]
TASK = ROOT / "generated_tasks" / "PutAppleBowl" / "v1"
# loops while it is imported: no reward API is involved, whatever shape that API takes
LOOP = "x = 0\nwhile True:\n    x = x + 1\n"
PARENT = (
    "import sys\n"
    "from generator.steps.probe import probe_task\n"
    "probe_task(sys.argv[1], [sys.argv[2]], steps=3, timeout_s=300, check_static=False)\n"
)
SETTLE_S = 10.0


def _stat(pid: int) -> tuple[int, str, int] | None:
    """(parent pid, state, start time) of ``pid`` from ``/proc``; None when it is gone."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text(encoding="ascii")
    except OSError:
        return None
    fields = text.rsplit(")", 1)[1].split()
    return int(fields[1]), fields[0], int(fields[19])


def _descendants(root: int) -> dict[int, int]:
    """{pid: start time} of every process below ``root``."""
    parents: dict[int, list[int]] = {}
    starts: dict[int, int] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit() and (st := _stat(int(entry.name))) is not None:
            parents.setdefault(st[0], []).append(int(entry.name))
            starts[int(entry.name)] = st[2]
    found, todo = {}, [root]
    while todo:
        for pid in parents.get(todo.pop(), []):
            found[pid] = starts[pid]
            todo.append(pid)
    return found


def _alive(pid: int, start: int) -> bool:
    st = _stat(pid)
    return st is not None and st[2] == start and st[1] != "Z"  # a zombie runs nothing; its new parent reaps it


def _probe_folders(tmpdir: Path) -> list[Path]:
    return sorted(tmpdir.glob("gendex_probe_*"))


@pytest.fixture
def task(tmp_path) -> tuple[Path, Path]:
    """A copy of a committed task and a module that loops at import."""
    folder = tmp_path / "task"
    shutil.copytree(TASK, folder)
    loop = folder / "loop.py"
    loop.write_text(LOOP, encoding="utf-8")
    return folder, loop


def _child_env(tmpdir: Path) -> dict[str, str]:
    env = dict(os.environ, TMPDIR=str(tmpdir))
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), *[p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p]])
    return env


def _wait_for_module(parent: subprocess.Popen, tmpdir: Path, timeout_s: float = 180) -> None:
    """Until the probe child has started running the module (its ``module`` progress event)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        assert parent.poll() is None, f"the parent exited early with {parent.returncode}"
        for folder in _probe_folders(tmpdir):
            try:
                if '"ev": "module"' in (folder / "progress.jsonl").read_text(encoding="utf-8"):
                    time.sleep(0.5)  # well inside the loop
                    return
            except OSError:
                pass
        time.sleep(0.1)
    pytest.fail(f"the probe child did not start the module within {timeout_s} s")


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM], ids=["SIGKILL", "SIGTERM"])
def test_killing_the_parent_mid_probe_leaves_no_process_and_no_folder(task, tmp_path, sig):
    folder, loop = task
    tmpdir = tmp_path / "tmp"
    tmpdir.mkdir()
    log = tmp_path / "parent.log"
    with open(log, "wb") as out:
        parent = subprocess.Popen([sys.executable, "-c", PARENT, str(folder), str(loop)], cwd=ROOT,
                                  env=_child_env(tmpdir), stdout=out, stderr=subprocess.STDOUT)
    try:
        _wait_for_module(parent, tmpdir)
        started = _descendants(parent.pid)
        assert len(started) >= 2, started  # the probe child and its reaper
        assert _probe_folders(tmpdir)
        t0 = time.monotonic()
        parent.send_signal(sig)
        parent.wait(timeout=SETTLE_S)
        while time.monotonic() - t0 < SETTLE_S:
            if not [p for p, s in started.items() if _alive(p, s)] and not _probe_folders(tmpdir):
                break
            time.sleep(0.05)
        left = {p: (_stat(p), Path(f"/proc/{p}/cmdline").read_bytes()) for p, s in started.items() if _alive(p, s)}
        assert not left, f"processes outlived the parent: {left}"
        assert not _probe_folders(tmpdir), "the probe's temporary folder outlived the parent"
        if sig == signal.SIGTERM:  # the parent cleaned up itself and exited as SIGTERM's default would
            assert parent.returncode == 128 + signal.SIGTERM, log.read_text(errors="replace")[-2000:]
        assert time.monotonic() - t0 < 5
    finally:
        if parent.poll() is None:
            parent.kill()
            parent.wait()


def test_a_hung_child_ends_itself_at_its_cpu_budget(task, tmp_path, monkeypatch):
    """The parent's wall-clock limit (300 s) never fires: the child's own RLIMIT_CPU stops the loop."""
    folder, loop = task
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", None)  # re-read TMPDIR
    t0 = time.monotonic()
    with pytest.raises(RewardProbeError) as err:
        probe_task(folder, [loop], steps=3, timeout_s=300, check_static=False, module_cpu_s=2)
    assert time.monotonic() - t0 < 120
    message = str(err.value)
    assert message.startswith("loop.py: the probe process exceeded its CPU budget of 2 s while importing the module "
                              "(infinite loop?); the kernel stopped it at line "), message
    assert not _probe_folders(tmp_path)


def test_the_reaper_kills_the_child_group_and_removes_the_folder_when_the_pipe_closes(tmp_path):
    work = tmp_path / "gendex_probe_x"
    work.mkdir()
    (work / "child.log").write_text("log", encoding="utf-8")
    sleeper = subprocess.Popen(["sleep", "60"], start_new_session=True)
    reaper = subprocess.Popen([sys.executable, "-m", "generator.steps.probe_child", "--reaper", str(work)],
                              stdin=subprocess.PIPE, cwd=ROOT, env=_child_env(tmp_path), text=True)
    reaper.stdin.write(f"{sleeper.pid}\n")
    reaper.stdin.close()  # as the kernel does when the parent dies: end of file, no "done"
    assert reaper.wait(timeout=10) == 1
    assert sleeper.wait(timeout=5) == -signal.SIGKILL
    assert not work.exists()


def test_the_reaper_leaves_everything_alone_after_done(tmp_path):
    work = tmp_path / "gendex_probe_y"
    work.mkdir()
    sleeper = subprocess.Popen(["sleep", "60"], start_new_session=True)
    try:
        reaper = subprocess.Popen([sys.executable, "-m", "generator.steps.probe_child", "--reaper", str(work)],
                                  stdin=subprocess.PIPE, cwd=ROOT, env=_child_env(tmp_path), text=True)
        reaper.stdin.write(f"{sleeper.pid}\ndone\n")
        reaper.stdin.close()
        assert reaper.wait(timeout=10) == 0
        assert work.is_dir() and sleeper.poll() is None
    finally:
        sleeper.kill()
        sleeper.wait()


def test_a_child_whose_parent_is_already_gone_exits_at_once(tmp_path):
    """The race PR_SET_PDEATHSIG leaves open: the parent died before the child's prctl."""
    job = tmp_path / "job.json"
    job.write_text(json.dumps({"parent_pid": 1, "progress": str(tmp_path / "progress.jsonl"), "modules": []}),
                   encoding="utf-8")
    t0 = time.monotonic()
    done = subprocess.run([sys.executable, "-m", "generator.steps.probe_child", str(job)], cwd=ROOT,
                          env=_child_env(tmp_path), timeout=30, capture_output=True)
    assert done.returncode == probe_child.ORPHANED_EXIT, done.stderr.decode()
    assert not (tmp_path / "progress.jsonl").exists()  # it stopped before writing anything
    assert time.monotonic() - t0 < 10
