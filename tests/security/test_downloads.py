"""``gendex dataset pull`` writes only inside ``--out`` (issue 43, deliverable 6).

A downloaded repo is hostile data: its build record names the task folders a pull writes, and its files may be
links or special files. Each hostile repo below sits on a :class:`FolderRemote` (no network); a sentinel folder
next to ``out`` must stay untouched, nothing outside ``out`` may be read into it, the error must be a
:class:`DatasetError` naming the bad entry, and ``out`` must be left as it was.
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import pytest

from gendex.data.datasets import BUILD_RECORD, DatasetError, FolderRemote, pull


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()} \
        if folder.exists() else {}


def _repo(tmp_path: Path, tasks: list[str], files: dict[str, str] | None = None, **record) -> FolderRemote:
    """A remote with one repo ``org/ds``: a build record naming ``tasks``, and ``files`` (path -> text)."""
    repo = tmp_path / "hub" / "org" / "ds"
    repo.mkdir(parents=True)
    (repo / BUILD_RECORD).write_text(json.dumps({"tasks": [{"task": t} for t in tasks], **record}))
    for rel, text in (files or {"data.parquet": "rows", "meta/info.json": "{}"}).items():
        (repo / rel).parent.mkdir(parents=True, exist_ok=True)
        (repo / rel).write_text(text)
    return FolderRemote(tmp_path / "hub")


@pytest.fixture
def places(tmp_path):
    """(out, sentinel): ``out`` already holds a file; ``sentinel`` is a folder beside it that nothing may touch."""
    out, sentinel = tmp_path / "work" / "out", tmp_path / "work" / "sentinel"
    (out / "keep").mkdir(parents=True)
    (out / "keep" / "mine.txt").write_text("the user's own file")
    sentinel.mkdir()
    (sentinel / "secret.txt").write_text("outside")
    return out, sentinel


def _refused(remote, out: Path, sentinel: Path, message: str) -> None:
    before_out, before_sentinel = _snapshot(out), _snapshot(sentinel)
    outside = {p for p in out.parent.parent.rglob("*")} - set(out.rglob("*")) - set(sentinel.rglob("*"))
    try:
        pull("org/ds", out, remote)
        error = None
    except DatasetError as exc:
        error = str(exc)
    assert _snapshot(sentinel) == before_sentinel, "a pull wrote outside --out"
    after = {p for p in out.parent.parent.rglob("*")} - set(out.rglob("*")) - set(sentinel.rglob("*"))
    assert {p for p in after - outside if "hub" not in p.parts} == set(), "a pull left files beside --out"
    assert _snapshot(out) == before_out, "a refused pull changed --out"
    assert error is not None and re.search(message, error), error


@pytest.mark.parametrize("name, message", [
    ("absolute", r"tasks\[0\]\.task .*is not a versioned GenDex task id"),
    ("dotdot", r"tasks\[0\]\.task .*is not a versioned GenDex task id"),
    ("newline", r"tasks\[0\]\.task .*is not a versioned GenDex task id"),
])
def test_a_task_name_that_leaves_out_is_refused(tmp_path, places, name, message):
    out, sentinel = places
    task = {"absolute": f"GenDex/{sentinel}", "dotdot": "GenDex/../sentinel", "newline": "GenDex/Put-v1\n"}[name]
    _refused(_repo(tmp_path, [task]), out, sentinel, message)
    assert not (sentinel / "lerobot").exists()


def test_a_later_task_name_that_leaves_out_refuses_the_whole_pull(tmp_path, places):
    """Several tasks: the repo's ``<task>/`` folders; a bad second name must not leave the first one half-written,
    nor read folders outside the download (``../``) into ``out``."""
    out, sentinel = places
    files = {"PutAppleBowl-v1/lerobot/data.parquet": "rows", "PutAppleBowl-v1/lerobot/meta/info.json": "{}"}
    remote = _repo(tmp_path, ["GenDex/PutAppleBowl-v1", "GenDex/../../../work/sentinel"], files)
    _refused(remote, out, sentinel, r"tasks\[1\]\.task")


def test_a_link_to_a_file_outside_is_refused_and_not_copied(tmp_path, places):
    out, sentinel = places
    remote = _repo(tmp_path, ["GenDex/PutAppleBowl-v1"])
    os.symlink(sentinel / "secret.txt", tmp_path / "hub" / "org" / "ds" / "meta" / "stolen.json")
    _refused(remote, out, sentinel, r"stolen\.json.*symbolic link")
    assert not any(p.read_bytes() == b"outside" for p in out.rglob("*") if p.is_file())


def test_a_special_file_is_refused(tmp_path, places):
    out, sentinel = places
    remote = _repo(tmp_path, ["GenDex/PutAppleBowl-v1"])
    os.mkfifo(tmp_path / "hub" / "org" / "ds" / "pipe")
    _refused(remote, out, sentinel, r"pipe.*not a regular file")


def test_a_huge_build_record_is_refused_before_it_is_parsed(tmp_path, places):
    out, sentinel = places
    remote = _repo(tmp_path, ["GenDex/PutAppleBowl-v1"], padding="x" * 2_000_000)
    _refused(remote, out, sentinel, r"MAX_BUILD_RECORD_BYTES")


def test_an_honest_repo_still_pulls_into_out_beside_what_was_there(tmp_path, places):
    out, _ = places
    pull("org/ds", out, _repo(tmp_path, ["GenDex/PutAppleBowl-v1"]))
    assert _snapshot(out) == {"keep/mine.txt": b"the user's own file", BUILD_RECORD: (
        tmp_path / "hub" / "org" / "ds" / BUILD_RECORD).read_bytes(), "PutAppleBowl-v1/lerobot/data.parquet": b"rows",
        "PutAppleBowl-v1/lerobot/meta/info.json": b"{}"}
    assert sorted(p.name for p in out.parent.iterdir()) == ["out", "sentinel"]  # no temporary folder left
