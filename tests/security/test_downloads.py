"""``gendex dataset pull`` writes only inside ``--out`` (issue 43, deliverable 6), and only so much.

A downloaded repo is hostile data: its build record names the task folders a pull writes, its files may be links or
special files, and it may hold any number of files of any size. Each hostile repo below sits on a
:class:`FolderRemote` or behind a stand-in of ``huggingface_hub.HfApi`` (no network); a sentinel folder next to
``out`` must stay untouched, nothing outside ``out`` may be read into it, the error must be a :class:`DatasetError`
naming the bad entry or the bound, and ``out`` must be left as it was. A repo over ``MAX_DOWNLOAD_FILES`` or
``MAX_DOWNLOAD_BYTES`` is refused before anything of it is copied (a Hub repo before anything is downloaded).
"""

from __future__ import annotations

import json
import os
import re
import shutil
from pathlib import Path
from types import SimpleNamespace

import pytest

from gendex.data import datasets
from gendex.data.datasets import BUILD_RECORD, DatasetError, FolderRemote, HubRemote, pull


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


# ---------------------------------------------------------------------------------------------- how much
def _flood(tmp_path: Path, kind: str, n: int, size: int = 0) -> FolderRemote:
    """An honest-looking one-task repo plus ``n`` files of ``size`` bytes (``kind == "files"``) or ``n`` empty
    folders under ``data/``."""
    remote = _repo(tmp_path, ["GenDex/PutAppleBowl-v1"])
    flood = tmp_path / "hub" / "org" / "ds" / "data" / "chunk-000"
    flood.mkdir(parents=True)
    for i in range(n):
        if kind == "files":
            (flood / f"file-{i:03d}.parquet").write_bytes(b"x" * size)
        else:
            (flood / f"empty-{i:03d}").mkdir()
    return remote


@pytest.fixture
def no_copy(monkeypatch):
    """Any ``shutil.copytree`` (the remote's copy into the download folder, the pull's copy towards ``out``) fails
    the test: the bounds must refuse a repo before anything of it is copied (and a regression copies nothing)."""

    def refuse(src, dst, *args, **kwargs):
        raise AssertionError(f"{src} was copied before the download's bounds were checked")

    monkeypatch.setattr(shutil, "copytree", refuse)


@pytest.mark.parametrize("kind", ["files", "folders"])
def test_a_download_with_too_many_entries_is_refused_before_copying(tmp_path, places, monkeypatch, no_copy, kind):
    out, sentinel = places
    monkeypatch.setattr(datasets, "MAX_DOWNLOAD_FILES", 40)
    _refused(_flood(tmp_path, kind, 60), out, sentinel,
             r"more than MAX_DOWNLOAD_FILES = 40 files and folders \(entry 41: ")


def test_a_download_over_the_byte_bound_is_refused_before_copying(tmp_path, places, monkeypatch, no_copy):
    out, sentinel = places
    monkeypatch.setattr(datasets, "MAX_DOWNLOAD_BYTES", 10_000)
    _refused(_flood(tmp_path, "files", 3, size=4_000), out, sentinel,
             r"files hold more than MAX_DOWNLOAD_BYTES = 10000 bytes \(1[0-9]{4} with '[^']*file-00[0-2]\.parquet'")


def test_a_sparse_file_counts_at_its_full_length(tmp_path, places, no_copy):
    """A 1 TB sparse file takes no disk in the repo, but a copy would write 1 TB: it is refused under the real bound
    (and never copied: ``no_copy``)."""
    out, sentinel = places
    remote = _repo(tmp_path, ["GenDex/PutAppleBowl-v1"])
    with (tmp_path / "hub" / "org" / "ds" / "data.parquet").open("r+b") as f:
        f.truncate(datasets.MAX_DOWNLOAD_BYTES * 5)
    _refused(remote, out, sentinel, rf"more than MAX_DOWNLOAD_BYTES = {datasets.MAX_DOWNLOAD_BYTES} bytes "
             r"\([0-9]+ with 'data\.parquet'\)")


@pytest.mark.parametrize("bound", ["files", "bytes"])
def test_the_copy_itself_counts_against_the_bounds(tmp_path, places, monkeypatch, bound):
    """As if the download had grown after the walk saw it (the walk switched off): the copy towards ``out`` stops at
    the bound, and the partial copy is removed."""
    out, sentinel = places
    monkeypatch.setattr(datasets, "regular_files_only", lambda root: None)
    if bound == "files":
        monkeypatch.setattr(datasets, "MAX_DOWNLOAD_FILES", 40)
        remote, message = _flood(tmp_path, "files", 60), r"more than MAX_DOWNLOAD_FILES = 40 files and folders"
    else:
        monkeypatch.setattr(datasets, "MAX_DOWNLOAD_BYTES", 10_000)
        remote, message = _flood(tmp_path, "files", 3, size=4_000), r"more than MAX_DOWNLOAD_BYTES = 10000 bytes"
    _refused(remote, out, sentinel, message)


class _Hub:
    """A stand-in of ``huggingface_hub.HfApi`` whose dataset repo lists ``siblings`` (``(name, size)``)."""

    def __init__(self, siblings: list[tuple[str, int | None]]):
        self.siblings, self.downloads = siblings, []

    def dataset_info(self, repo_id, *, files_metadata=False):
        assert files_metadata, "without files_metadata the Hub lists no sizes"
        siblings = [SimpleNamespace(rfilename=n, size=s) for n, s in self.siblings]
        return SimpleNamespace(sha="0123abcd", siblings=siblings)

    def snapshot_download(self, **kw):
        self.downloads.append(kw)
        raise AssertionError("downloaded a repo whose listing is over the bounds")


@pytest.mark.parametrize("case, message", [
    ("many", r"more than MAX_DOWNLOAD_FILES = 40 files and folders \(entry 41: 'data/chunk-000/file-0[0-9]{2}"),
    ("big", r"more than MAX_DOWNLOAD_BYTES = [0-9]+ bytes \([0-9]+ with 'data/chunk-000/file-000\.parquet'\)"),
    ("no_size", r"lists 'data/chunk-000/file-000\.parquet' without a size"),
    ("deep", r"is nested more than MAX_DOWNLOAD_DEPTH = 32 folders deep"),
])
def test_a_hub_repo_over_the_bounds_is_refused_before_anything_is_downloaded(tmp_path, places, monkeypatch, case,
                                                                            message):
    out, sentinel = places
    monkeypatch.setattr(datasets, "MAX_DOWNLOAD_FILES", 40)
    listing = [(BUILD_RECORD, 100), ("meta/info.json", 2)]
    listing += {"many": [(f"data/chunk-000/file-{i:03d}.parquet", 10) for i in range(60)],
                "big": [("data/chunk-000/file-000.parquet", datasets.MAX_DOWNLOAD_BYTES)],
                "no_size": [("data/chunk-000/file-000.parquet", None)],
                "deep": [("a/" * 40 + "data.parquet", 10)]}[case]
    api = _Hub(listing)
    _refused(HubRemote(api=api), out, sentinel, message)
    assert api.downloads == []


def test_the_bounds_leave_room_for_the_published_datasets():
    """Every manifest in ``datasets/``, at generous guesses of its size (1 MB of video per episode and camera, 100 kB
    of state data per episode, every file of a task's LeRobot dataset and its folders), fits ten times over."""
    manifests = sorted(datasets.DATASETS_DIR.glob("*.yaml"))
    assert manifests
    for path in manifests:
        m = datasets.load_manifest(path)
        cams, episodes = len(m.cameras), sum(t.episodes for t in m.tasks)
        entries = 1 + sum(14 + cams * (2 + t.episodes) for t in m.tasks)
        assert entries >= len(m.checksums), m.name
        assert 10 * entries <= datasets.MAX_DOWNLOAD_FILES, (m.name, entries)
        assert 10 * episodes * (100_000 + cams * 1_000_000) <= datasets.MAX_DOWNLOAD_BYTES, m.name
