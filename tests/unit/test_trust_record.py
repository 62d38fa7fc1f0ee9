"""The trust record (generated_tasks/TRUSTED.sha256, gendex_envs.trust_record): code in the repository's task folder is
trusted only when its bytes are the recorded ones, so model-written code that lands there (``gendex generate``'s
default ``--out``) is untrusted until a person records it with ``gendex trust``."""

from __future__ import annotations

import os
import shutil
import subprocess
import time

import pytest
from typer.testing import CliRunner

from gendex_envs import guard, registry, trust_record
from gendex_envs.errors import RewardModuleError
from gendex_envs.registry import REPO_TASKS_DIR
from gendex_envs.reward_module import load_reward_module
from gendex_envs.task_version import TaskLayout
from gendex_envs.trust_record import RECORD_NAME, TrustRecordError, parse_record, record_trusted, render_record

REWARD = "PutAppleBowl/v1/reward.py"
STAGE = "PutAppleBowl/v1/stage_rewards/grasp_apple.py"


def _committed_code_files() -> list[str]:
    """The ``.py`` files git holds under generated_tasks/ (the folder walked when this is not a git checkout)."""
    try:
        out = subprocess.run(["git", "ls-files", "-z", "--", "*.py"], cwd=REPO_TASKS_DIR, capture_output=True,
                             check=True, timeout=60).stdout.decode()
        return sorted(p for p in out.split("\0") if p)
    except (OSError, subprocess.SubprocessError):
        return trust_record.code_files()


def test_the_record_lists_exactly_the_committed_code_files():
    files = _committed_code_files()
    assert len(files) >= 500, files[:5]
    raw = (REPO_TASKS_DIR / RECORD_NAME).read_bytes()
    status = trust_record.trust_status(files)
    assert status.clean, ("generated_tasks/TRUSTED.sha256 does not match the committed reward code:\n  "
                          + "\n  ".join(status.lines()[:20])
                          + "\nReview the tasks, then run `gendex trust generated_tasks/<Name>/v<N>` (or `gendex trust "
                            "--check` to list them) and commit generated_tasks/TRUSTED.sha256 with them")
    assert raw.decode() == render_record(parse_record(raw)), ("generated_tasks/TRUSTED.sha256 is not sorted as "
                                                               "`gendex trust` writes it; run `gendex trust "
                                                               "generated_tasks/<Name>/v<N>` on any task to rewrite it")


def test_committed_modules_are_trusted_by_their_bytes(monkeypatch):
    monkeypatch.delenv(guard.TRUST_ENV, raising=False)
    monkeypatch.setattr(guard, "_trusted_extra", set())  # whatever earlier tests trusted with trust_remote_code
    path = REPO_TASKS_DIR / REWARD
    assert guard.is_trusted(path) and guard.is_trusted(REPO_TASKS_DIR / STAGE)
    assert guard.is_trusted(path.parent)  # a folder: every .py file in it is recorded
    assert guard.is_trusted(path, path.read_bytes())
    assert not guard.is_trusted(path, path.read_bytes() + b"\n# changed\n")  # the bytes judged are the bytes given
    assert not guard.is_trusted(REPO_TASKS_DIR / "PutAppleBowl" / "v1" / "extra.py")


# ---------------------------------------------------------------------------------------------- a scratch task folder
@pytest.fixture
def tasks(tmp_path, monkeypatch, task_version):
    """A scratch repository task folder (``registry.REPO_TASKS_DIR``) holding PutAppleBowl/v1, recorded."""
    root = (tmp_path / "repo" / "generated_tasks").resolve()
    shutil.copytree(task_version("PutAppleBowl", 1).root, root / "PutAppleBowl" / "v1",
                    ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(registry, "REPO_TASKS_DIR", root)
    monkeypatch.delenv(guard.TRUST_ENV, raising=False)
    monkeypatch.setattr(guard, "_trusted_extra", set())
    trust_record.forget()
    update = record_trusted([root / "PutAppleBowl"])
    assert len(update.added) == 5 and not update.changed
    yield root
    trust_record.forget()


def test_a_recorded_file_is_trusted_and_loads_in_process(tasks):
    path = tasks / REWARD
    assert guard.is_trusted(path) and guard.is_trusted(tasks / STAGE)
    module = load_reward_module(path)
    assert module.path == path and not any(str(tasks) in f for f in guard.untrusted_folders())


def test_a_new_file_in_the_tasks_folder_is_untrusted(tasks, tmp_path):
    new = tasks / "PutAppleBowl" / "v2" / "reward.py"
    shutil.copytree(tasks / "PutAppleBowl" / "v1", new.parent)
    assert not guard.is_trusted(new), "identical bytes at an unrecorded path are not trusted: the path is recorded"
    assert not guard.is_trusted(new.parent)
    marker = tmp_path / "marker"
    fresh = tasks / "Fresh" / "v0" / "reward.py"
    fresh.parent.mkdir(parents=True)
    fresh.write_text(f"import os\nopen({str(marker)!r}, 'w').write('ran')\n" + (tasks / REWARD).read_text())
    assert not guard.is_trusted(fresh)
    with pytest.raises(RewardModuleError, match="is not trusted .*static check rejected it"):
        load_reward_module(fresh)
    assert not marker.exists()


def test_a_changed_file_is_untrusted_and_trusted_again_when_restored(tasks, tmp_path):
    path = tasks / REWARD
    original = path.read_bytes()
    assert guard.is_trusted(path)
    marker = tmp_path / "marker"
    path.write_bytes(original + f"\nopen({str(marker)!r}, 'w').write('ran')\n".encode())
    assert not guard.is_trusted(path) and not guard.is_trusted(path.parent)
    with pytest.raises(RewardModuleError, match="is not trusted"):
        load_reward_module(path)
    assert not marker.exists()
    path.write_bytes(original)
    assert guard.is_trusted(path)


def test_a_same_size_change_with_its_mtime_put_back_is_seen(tasks, monkeypatch):
    monkeypatch.setattr(trust_record, "RACY_NS", 0)  # cache even a file written just now
    path = tasks / REWARD
    original = path.read_bytes()
    before = path.stat()
    assert guard.is_trusted(path) and guard.is_trusted(path)  # the second answer is the cached digest
    time.sleep(0.05)  # past the file system's time stamp tick
    path.write_bytes(original.replace(b"import", b"impart", 1))
    os.utime(path, ns=(before.st_atime_ns, before.st_mtime_ns))
    assert path.stat().st_size == before.st_size and path.stat().st_mtime_ns == before.st_mtime_ns
    assert not guard.is_trusted(path)


def test_bytes_that_change_while_loading_are_refused(tasks, monkeypatch):
    import gendex_envs.reward_module as reward_module

    path = tasks / REWARD
    monkeypatch.setattr(reward_module, "read_reward_bytes", lambda p: path.read_bytes() + b"\nX = 1\n")
    with pytest.raises(RewardModuleError, match="changed while it was being loaded"):
        load_reward_module(path)


def test_links_are_judged_where_they_lie(tasks, tmp_path):
    outside = tmp_path / "outside.py"
    outside.write_bytes((tasks / REWARD).read_bytes())
    (tasks / REWARD).unlink()
    (tasks / REWARD).symlink_to(outside)  # recorded path, recorded bytes, but a link
    assert not guard.is_trusted(tasks / REWARD)
    with pytest.raises(TrustRecordError, match="link"):
        record_trusted([tasks / REWARD])


@pytest.mark.parametrize("text", [
    b"zz" * 32 + b"  PutAppleBowl/v1/reward.py\n",                     # not hex
    b"ab" * 32 + b" PutAppleBowl/v1/reward.py\n",                       # one space
    b"AB" * 32 + b"  PutAppleBowl/v1/reward.py\n",                      # upper case
    b"ab" * 32 + b"  /etc/reward.py\n",                                 # absolute
    b"ab" * 32 + b"  PutAppleBowl/../reward.py\n",                      # ..
    b"ab" * 32 + b"  .drafts/abc/reward.py\n",                          # hidden folder
    b"ab" * 32 + b"  PutAppleBowl/v1/task.yaml\n",                      # not code
    b"ab" * 32 + b"  PutAppleBowl/v1/reward.py",                        # no final newline
    b"ab" * 32 + b"  PutAppleBowl/v1/reward.py\r\n",                    # CR
    b"ab" * 32 + b"  PutAppleBowl/v1/reward.py\n\n",                    # empty line
    b"ab" * 32 + b"  PutAppleBowl/v1/reward.py\n" + b"cd" * 32 + b"  PutAppleBowl/v1/reward.py\n",  # twice
    "ab" * 32 + "  PutAppleBowl/v1/r\u00e9ward.py\n",                  # not ASCII
], ids=["hex", "space", "case", "absolute", "dotdot", "hidden", "yaml", "newline", "cr", "empty", "twice", "ascii"])
def test_a_malformed_record_trusts_nothing(tasks, text, caplog):
    record = tasks / RECORD_NAME
    data = text.encode() if isinstance(text, str) else text
    record.write_bytes(record.read_bytes() + data)
    with pytest.raises(TrustRecordError):
        parse_record(data)
    trust_record.forget()
    with caplog.at_level("ERROR", logger="gendex_envs.trust_record"):
        assert not guard.is_trusted(tasks / REWARD) and not guard.is_trusted(tasks / STAGE)
    assert "trust record is malformed" in caplog.text and str(record) in caplog.text
    with pytest.raises(TrustRecordError):
        record_trusted([tasks / "PutAppleBowl"])  # nothing is guessed: a person fixes the record


@pytest.mark.parametrize("how", ["missing", "link", "oversize"])
def test_a_missing_linked_or_oversized_record_trusts_nothing(tasks, how, tmp_path, caplog, monkeypatch):
    record = tasks / RECORD_NAME
    if how == "missing":
        record.unlink()
    elif how == "link":
        moved = tmp_path / "elsewhere.sha256"
        record.rename(moved)
        record.symlink_to(moved)
    else:
        monkeypatch.setattr(trust_record, "MAX_RECORD_BYTES", record.stat().st_size - 1)
    trust_record.forget()
    with caplog.at_level("WARNING", logger="gendex_envs.trust_record"):
        assert not guard.is_trusted(tasks / REWARD)
    assert ("no trust record" if how == "missing" else "malformed") in caplog.text


def test_trust_remote_code_and_the_environment_still_trust_an_unrecorded_file(tasks, monkeypatch):
    path = tasks / "Fresh" / "v0" / "reward.py"
    path.parent.mkdir(parents=True)
    path.write_bytes((tasks / REWARD).read_bytes())
    assert not guard.is_trusted(path)
    monkeypatch.setenv(guard.TRUST_ENV, "1")
    assert guard.is_trusted(path)
    monkeypatch.delenv(guard.TRUST_ENV)
    guard.trust(path.parent)
    assert guard.is_trusted(path)


def test_a_task_the_generate_path_writes_into_the_tasks_folder_is_untrusted_until_recorded(tasks):
    """``gendex generate`` publishes a finished task with BuiltTask.publish (or publish, the same step) into its
    ``--out``, ``generated_tasks/`` by default; it never touches the record."""
    from generator.pipeline import BuiltTask

    source = TaskLayout(tasks / "PutAppleBowl" / "v1")
    files = {p.relative_to(source.root).as_posix(): p.read_bytes() for p in sorted(source.root.rglob("*"))
             if p.is_file()}
    files |= {"proposal.json": b"{}\n", "generation.json": b"{}\n", "transcript.jsonl": b""}
    record = (tasks / RECORD_NAME).read_bytes()
    summary = BuiltTask("GeneratedApple", files, dict(candidate_violations=(0.0,), violations_before=0,
                                                      violations_after=0, refine_rounds=0, seconds=0.0)).publish(tasks)
    new = summary.committed.files
    assert new.root.is_relative_to(tasks) and new.reward.read_bytes() == source.reward.read_bytes()
    assert (tasks / RECORD_NAME).read_bytes() == record, "publishing a generated task changed the trust record"
    modules = TaskLayout(new.root).reward_modules()
    assert len(modules) == 5 and not any(guard.is_trusted(m) for m in modules)
    assert trust_record.trust_status().unrecorded == tuple(sorted(m.relative_to(tasks).as_posix() for m in modules))
    update = record_trusted([new.root])  # the person's step
    assert len(update.added) == 5 and all(guard.is_trusted(m) for m in modules)
    assert trust_record.trust_status().clean


def test_recording_refuses_folders_outside_the_tasks_folder_and_drafts(tasks, tmp_path):
    elsewhere = tmp_path / "Downloaded" / "v0"
    shutil.copytree(tasks / "PutAppleBowl" / "v1", elsewhere)
    with pytest.raises(TrustRecordError, match="not in the repository's task folder"):
        record_trusted([elsewhere])
    draft = tasks / ".drafts" / "abc123"
    shutil.copytree(tasks / "PutAppleBowl" / "v1", draft)
    with pytest.raises(TrustRecordError, match="cannot be recorded"):
        record_trusted([draft])
    assert not guard.is_trusted(draft / "reward.py")


def test_recording_drops_entries_of_removed_files(tasks):
    (tasks / STAGE).unlink()
    assert trust_record.trust_status().stale == (STAGE,)
    update = record_trusted([tasks / REWARD])
    assert update.dropped == (STAGE,) and update.unchanged == (REWARD,)
    assert trust_record.trust_status().clean


def test_the_trust_command_checks_and_records(tasks):
    from gendex.cli import app

    runner = CliRunner()
    assert runner.invoke(app, ["trust", "--check"]).exit_code == 0
    new = tasks / "PutAppleBowl" / "v2"
    shutil.copytree(tasks / "PutAppleBowl" / "v1", new)
    result = runner.invoke(app, ["trust"])
    assert result.exit_code == 1 and "not recorded (untrusted): PutAppleBowl/v2/reward.py" in result.output
    result = runner.invoke(app, ["trust", str(new)])
    assert result.exit_code == 0, result.output
    assert "5 added" in result.output and guard.is_trusted(new / "reward.py")
    assert runner.invoke(app, ["trust", "--check"]).exit_code == 0
    result = runner.invoke(app, ["trust", str(tasks.parent)])
    assert result.exit_code == 2 and "not in the repository's task folder" in result.output
