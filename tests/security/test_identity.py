"""Identity and availability of task ids (issue 43, round two).

- One malformed folder on ``GENDEX_TASKS_PATH`` (a ``task.yaml`` that is a folder or a FIFO, a version folder whose
  name only looks like ``v<N>``, a missing root) is reported and skipped; ``import gendex_envs`` succeeds and every
  other task registers.
- A folder that would replace a committed task id is refused unless asked for (``GENDEX_ALLOW_OVERRIDE=1`` or
  ``register_tasks(..., override=True)``).

Imports run in a fresh interpreter, as a user's would.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import pytest

from gendex_envs.registry import (
    ALLOW_OVERRIDE_ENV,
    REPO_TASKS_DIR,
    discover_tasks,
    register_tasks,
    registered_tasks,
    unregister_tasks,
)
from gendex_envs.task_version import TaskLayout, TaskVersion

REPO = Path(__file__).resolve().parents[2]
SOURCE = REPO_TASKS_DIR / "PutAppleBowl" / "v0"
COMMITTED = "GenDex/PutAppleBowl-v0"


def _copy(root: Path, name: str, version_dir: str = "v0", spec_name: str | None = None) -> Path:
    folder = root / name / version_dir
    shutil.copytree(SOURCE, folder)
    spec = TaskLayout(folder).spec
    spec.write_text(spec.read_text().replace("name: PutAppleBowl\n", f"name: {spec_name or name}\n"))
    return folder


def _import(tasks_path: str, **env: str) -> tuple[dict, str]:
    """Import gendex_envs in a fresh interpreter; (registered id -> folder, stderr)."""
    code = ("import json, gendex_envs, gymnasium as gym\n"
            "ids = gendex_envs.registered_tasks()\n"
            "assert all(i in gym.registry for i in ids)\n"
            "print(json.dumps({i: str(v.root) for i, v in ids.items()}))\n")
    environ = {k: v for k, v in os.environ.items() if k not in ("GENDEX_TASKS_PATH", ALLOW_OVERRIDE_ENV)}
    environ.update(GENDEX_TASKS_PATH=tasks_path, PYTHONPATH=str(REPO), **env)
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, env=environ, capture_output=True, text=True,
                          timeout=240)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1]), done.stderr


def test_one_bad_folder_is_reported_and_skipped_the_rest_register(tmp_path):
    root = tmp_path / "tasks"
    good = _copy(root, "ExtraApple")
    dir_spec = _copy(root, "DirSpec")
    TaskLayout(dir_spec).spec.unlink()
    TaskLayout(dir_spec).spec.mkdir()  # task.yaml is a folder
    fifo = _copy(root, "FifoSpec")
    TaskLayout(fifo).spec.unlink()
    os.mkfifo(TaskLayout(fifo).spec)  # reading it would block forever
    _copy(root, "NewlineVersion", version_dir="v1\n")  # only looks like v1
    _copy(root, "DigitVersion", version_dir="v\u0661")  # an Arabic-Indic one: int() reads it as 1
    _copy(root, "Newline\n", spec_name='"Newline\\n"')  # the name regex's $ matched before a final newline
    wrong = _copy(root, "WrongName", spec_name="OtherName")
    missing, a_file = tmp_path / "not-there", tmp_path / "a-file"
    a_file.write_text("not a folder")

    ids, log = _import(os.pathsep.join([str(missing), str(root), str(a_file)]))

    assert ids["GenDex/ExtraApple-v0"] == str(good)
    committed = set(discover_tasks([REPO_TASKS_DIR]))
    assert len(committed) >= 190 and committed <= set(ids)
    assert all(Path(ids[i]).is_relative_to(REPO_TASKS_DIR) for i in committed)
    assert set(ids) == committed | {"GenDex/ExtraApple-v0"}  # nothing of the bad folders
    for reported in (dir_spec, fifo, wrong, missing, a_file):
        assert str(reported) in log, f"{reported} is not reported:\n{log}"
    for reported in ("NewlineVersion", "DigitVersion", "Newline"):
        assert f"{root}{os.sep}{reported}" in log, f"{reported} is not reported:\n{log}"


def test_register_tasks_skips_a_folder_whose_spec_raises_anything(tmp_path, monkeypatch, caplog):
    """A spec loader that raises something other than TaskSpecError still skips only that version."""
    root = tmp_path / "tasks"
    _copy(root, "BoomApple")
    _copy(root, "FineApple")

    real = TaskVersion.load_spec_unchecked

    def boom(self):
        if self.name == "BoomApple":
            raise RecursionError("maximum recursion depth exceeded")
        return real(self)

    monkeypatch.setattr(TaskVersion, "load_spec_unchecked", boom)
    try:
        assert register_tasks([root]) == ["GenDex/FineApple-v0"]
        assert "BoomApple" in caplog.text and "RecursionError" in caplog.text
    finally:
        unregister_tasks(["GenDex/FineApple-v0"])


def test_a_folder_on_the_tasks_path_cannot_replace_a_committed_id(tmp_path):
    root = tmp_path / "tasks"
    shadow = _copy(root, "PutAppleBowl")
    reward = TaskLayout(shadow).reward
    reward.write_text(reward.read_text() + "\n# changed: a different reward under the committed id\n")

    ids, log = _import(str(root))
    assert ids[COMMITTED] == str(SOURCE)  # the committed version keeps its id
    assert str(shadow) in log and "committed" in log and ALLOW_OVERRIDE_ENV in log

    ids, log = _import(str(root), **{ALLOW_OVERRIDE_ENV: "1"})  # asked for: the folder replaces it
    assert ids[COMMITTED] == str(shadow)
    assert ids["GenDex/PutAppleBowl-v1"] == str(REPO_TASKS_DIR / "PutAppleBowl" / "v1")


def test_register_tasks_refuses_a_committed_id_unless_override(tmp_path, caplog, monkeypatch):
    monkeypatch.delenv(ALLOW_OVERRIDE_ENV, raising=False)
    root = tmp_path / "tasks"
    shadow = _copy(root, "PutAppleBowl")
    assert register_tasks([root]) == []
    assert registered_tasks()[COMMITTED].root == SOURCE and gym.spec(COMMITTED).kwargs["task"] == str(SOURCE)
    assert str(shadow) in caplog.text and "override=True" in caplog.text
    try:
        assert register_tasks([root], override=True) == [COMMITTED]
        assert registered_tasks()[COMMITTED].root == shadow and gym.spec(COMMITTED).kwargs["task"] == str(shadow)
    finally:
        assert register_tasks([REPO_TASKS_DIR], override=True) == [COMMITTED]  # put the committed one back
    assert registered_tasks()[COMMITTED].root == SOURCE


def test_the_override_variable_is_read_like_the_trust_variable(monkeypatch, tmp_path):
    from gendex_envs.registry import override_allowed

    for value, allowed in (("1", True), ("true", True), ("YES", True), ("0", False), ("", False), ("no", False)):
        monkeypatch.setenv(ALLOW_OVERRIDE_ENV, value)
        assert override_allowed() is allowed
    monkeypatch.delenv(ALLOW_OVERRIDE_ENV)
    assert override_allowed() is False


def test_a_task_copy_under_another_name_still_registers(task_copy):
    copy = task_copy("PutAppleBowl", as_name="ScratchIdentity", version=4)
    assert registered_tasks()["GenDex/ScratchIdentity-v4"] == copy


@pytest.mark.parametrize("bad", ["v1\n", "v\u0661", "v01"])
def test_versions_in_skips_lookalike_version_folders(tmp_path, bad, caplog):
    from gendex_envs.task_version import versions_in

    _copy(tmp_path, "LookApple", version_dir=bad)
    _copy(tmp_path, "LookApple", version_dir="v2")
    assert [v.env_id for v in versions_in(tmp_path)] == ["GenDex/LookApple-v2"]
    assert repr(bad) in caplog.text or bad in caplog.text
