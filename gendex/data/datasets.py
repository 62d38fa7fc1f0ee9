"""Published datasets: a manifest per dataset in ``datasets/``, and building, verifying, pushing and pulling them.

A manifest (``datasets/<name>.yaml``) says what a dataset is: its tasks with episodes and seeds per task, the
solver, cameras, resolution and video codec, the stats' ``conventions`` (1, the default: as published; 2: lerobot
0.4's, with quantiles; 3: as 2, quantiles over all frames), the GenDex version, and the SHA-256 of every file of the
built dataset. From it,

- :func:`build` collects each task with ``gendex.data.collector`` into ``<out>/<task>/`` (a LeRobot v3.0 dataset
  in ``lerobot/`` with its card; resumable: a killed build goes on where it stopped; ``workers`` processes per task)
  and writes ``<out>/gendex_dataset.json`` (the manifest as built, what each collection took);
- :func:`verify` checks a built or downloaded copy against the manifest, file by file: a missing, extra or
  different file is named. Collection is deterministic (an episode depends only on task version, seed and actions,
  and the planner is seeded per episode), so a build reproduces the manifest's checksums byte for byte;
- :func:`push` and :func:`pull` move a built dataset to and from a remote: the Hugging Face Hub
  (:class:`HubRemote`, ``huggingface_hub``) or a folder (:class:`FolderRemote`, a file-backed stand-in with the
  same interface, which the tests use: this machine has no network). A one-task dataset is pushed with its LeRobot
  dataset at the repo's root (``LeRobotDataset(repo_id)`` loads it; its card carries the ``LeRobot`` tag) and the
  ``v3.0`` git tag lerobot loads it at is put on the commit just pushed (moved there from an earlier push's);
  several tasks go in ``<task>/`` folders. A pull restores the build's layout, so the copy verifies against the
  manifest.

Checksums cover every file of each task's ``lerobot/`` folder (data, meta, videos, card) and ``gendex_dataset.json``;
the collector's bookkeeping (``collect_state.json``, which holds wall-clock time) is left out.

A pulled repo is untrusted data. Before anything reaches ``out``, :func:`pull` refuses (:class:`DatasetError` naming
the entry) a symbolic link or any other non-regular file anywhere in the download, a download of more than
``MAX_DOWNLOAD_FILES`` files and folders or ``MAX_DOWNLOAD_BYTES`` bytes (the Hub's listing is checked before
anything is downloaded, the files on disk before anything is copied, and the copy counts again), a build record over
``MAX_BUILD_RECORD_BYTES`` (checked before parsing; parsed with the bounded JSON loader), and a task that is not a
versioned GenDex id ``GenDex/<Name>-v<N>`` (so its folder is a plain name: no ``/``, ``..``, absolute path or
newline); every joined path must resolve inside its folder. The copy is assembled in a hidden folder beside
``out`` and moved in only when complete, so a refused pull leaves ``out`` as it was.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import re
import shutil
import stat
import tempfile
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Protocol

import dacite
import yaml

from gendex.data import numerics
from gendex.data.episode import EpisodeError
from gendex.data.provenance import BuiltWith
from gendex.fanout import Backend, session
from gendex_envs.atomic_io import atomic_dir, write_text
from gendex_envs.library import library_dir
from gendex_envs.typed_yaml import load_yaml_bounded, parse_json_bounded, quote

log = logging.getLogger(__name__)

DATASETS_DIR = library_dir("datasets")  # the checkout's datasets/, or the installed wheel's (gendex_envs.library)
BUILD_RECORD = "gendex_dataset.json"
MAX_BUILD_RECORD_BYTES = 1_000_000
"""A build record (``gendex-smoke``'s is 1 KB; 10 tasks of 1 000 episodes about 100 KB)."""
MAX_BUILD_RECORD_NODES = 200_000
"""Values in a build record (each kept seed is one)."""
TASK_ID = re.compile(r"GenDex/([A-Z][A-Za-z0-9]{0,99}-v[0-9]{1,9})")
"""A versioned task id as a build record names it; group 1 is the task's folder in a build (used with fullmatch)."""
SKIPPED = ("collect_state.json",)
"""Files a build writes that are not part of the dataset (bookkeeping with wall-clock times)."""


class DatasetError(EpisodeError):
    """A manifest is malformed or unknown, or a dataset does not match its manifest."""


@dataclass(frozen=True)
class DatasetTask:
    task: str
    """A versioned Gymnasium id, e.g. ``GenDex/PutAppleBowl-v1``."""
    episodes: int
    """Successful episodes to keep."""
    seed: int = 0
    """Attempt k resets with ``seed + k``."""
    max_attempts: int | None = None
    """Give up after this many attempts (default: the collector's, 20 x episodes)."""


@dataclass(frozen=True)
class DatasetManifest:
    name: str
    description: str
    tasks: tuple[DatasetTask, ...]
    gendex_version: str
    solver: str = "stages"
    cameras: tuple[str, ...] = ()
    resolution: int = 128
    video_codec: str | None = "libsvtav1"
    conventions: int = 1
    """The LeRobot conventions of the built dataset's stats: 1 (the default, what the published manifests build)
    min/max/mean/std/count; 2 lerobot 0.4's, also the quantiles q01/q10/q50/q90/q99 (:mod:`gendex.data.lerobot_v3`);
    3 as 2, with ``stats.json``'s quantiles over all frames (what pi0.5's normalisation needs). Written to the
    manifest file and the build record only when it is not 1, so those stay as published."""
    checksums: dict[str, str] = field(default_factory=dict)
    """Path in the built dataset -> SHA-256 (hex) of its bytes; empty until a build was recorded."""
    built_with: BuiltWith | None = None
    """The code that built the recorded checksums (:mod:`gendex.data.provenance`); None before it was recorded."""

    def folder(self, task: DatasetTask) -> str:
        """The sub-folder of a built dataset holding ``task`` (``PutAppleBowl-v1``)."""
        return task.task.split("/", 1)[-1]


def _check(m: DatasetManifest) -> DatasetManifest:
    from gendex.data.lerobot_files import CONVENTIONS
    from gendex.solve import SOLVERS
    from gendex_envs.video import CODECS

    problems = []
    if not m.tasks:
        problems.append("tasks is empty")
    names = [m.folder(t) for t in m.tasks]
    if len(set(names)) != len(names):
        problems.append(f"a task is listed twice: {names}")
    for t in m.tasks:
        if not t.task.startswith("GenDex/") or "-v" not in t.task:
            problems.append(f"task {t.task!r} is not a versioned GenDex id (GenDex/<Name>-v<N>)")
        if t.episodes < 1 or (t.max_attempts is not None and t.max_attempts < t.episodes):
            problems.append(f"{t.task}: episodes ({t.episodes}) must be >= 1 and <= max_attempts ({t.max_attempts})")
    if m.solver not in SOLVERS:
        problems.append(f"solver {m.solver!r} is not one of {sorted(SOLVERS)}")
    if m.video_codec is not None and m.video_codec not in CODECS:
        problems.append(f"video_codec {m.video_codec!r} is not one of {sorted(CODECS)} or null")
    if type(m.conventions) is not int or m.conventions not in CONVENTIONS:
        problems.append(f"conventions {m.conventions!r} is not one of {list(CONVENTIONS)} (1: stats as published; "
                        "2: lerobot 0.4's, with quantiles; 3: as 2, quantiles over all frames)")
    if problems:
        raise DatasetError(f"dataset manifest {m.name!r}: " + "; ".join(problems))
    return m


def manifest_path(name: str) -> Path:
    """``datasets/<name>.yaml``; a path to a manifest file is taken as it is."""
    p = Path(name)
    return p if p.suffix in (".yaml", ".yml") and p.is_file() else DATASETS_DIR / f"{name}.yaml"


def load_manifest(name: str | Path) -> DatasetManifest:
    """The manifest ``datasets/<name>.yaml`` (or a manifest file), checked."""
    path = manifest_path(str(name))
    if not path.is_file():
        known = sorted(p.stem for p in DATASETS_DIR.glob("*.yaml"))
        raise DatasetError(f"no dataset manifest {name!r}; known: {', '.join(known) or 'none'} (in {DATASETS_DIR})")
    raw = load_yaml_bounded(path.read_bytes(), str(path), DatasetError)  # a manifest may come from anyone
    try:
        m = dacite.from_dict(DatasetManifest, raw, config=dacite.Config(strict=True, cast=[tuple]))
    except (dacite.DaciteError, TypeError) as exc:
        raise DatasetError(f"{path}: {exc}") from exc
    if m.name != path.stem:
        raise DatasetError(f"{path}: name {m.name!r} must equal the file's name {path.stem!r}")
    return _check(m)


def save_manifest(m: DatasetManifest, path: Path) -> None:
    """Write ``m`` as YAML (checksums sorted by path)."""
    raw = asdict(m)
    raw["tasks"] = [{k: v for k, v in t.items() if v is not None} for t in raw["tasks"]]
    raw["cameras"] = list(m.cameras)
    raw["checksums"] = dict(sorted(m.checksums.items()))
    if m.built_with is None:
        raw.pop("built_with")
    if m.conventions == 1:  # the default: the published manifests do not name it
        raw.pop("conventions")
    header = (f"# GenDex dataset manifest: `gendex dataset build {m.name}` collects it, `gendex dataset verify`\n"
              "# checks a copy against the checksums (written by `gendex dataset build --record`). See\n"
              "# docs/datasets.md.\n")
    write_text(path, header + yaml.safe_dump(raw, sort_keys=False, width=110))


# --------------------------------------------------------------------------------------------- checksums
def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with path.open("rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def checksums(root: Path) -> dict[str, str]:
    """Relative path -> SHA-256 of every file of the built dataset at ``root`` (bookkeeping and temp files left
    out)."""
    root = Path(root)
    return {str(p.relative_to(root)): _sha256(p) for p in sorted(root.rglob("*"))
            if p.is_file() and p.name not in SKIPPED and not p.name.startswith(".")}


@dataclass(frozen=True)
class Verification:
    missing: tuple[str, ...]
    extra: tuple[str, ...]
    different: tuple[str, ...]
    checked: int

    @property
    def ok(self) -> bool:
        return not (self.missing or self.extra or self.different)

    def summary(self) -> str:
        if self.ok:
            return f"{self.checked} files match the manifest"
        parts = [f"{len(v)} {k} ({', '.join(v[:3])}{', ...' if len(v) > 3 else ''})"
                 for k, v in (("missing", self.missing), ("extra", self.extra), ("different", self.different)) if v]
        return "; ".join(parts)


def verify(root: Path, manifest: DatasetManifest) -> Verification:
    """Compare the dataset at ``root`` with ``manifest``'s checksums; :class:`DatasetError` when the manifest has
    none yet (build it with ``--record`` first)."""
    if not manifest.checksums:
        raise DatasetError(f"manifest {manifest.name!r} holds no checksums yet: record them with "
                           f"`gendex dataset build {manifest.name} --record`")
    if not Path(root).is_dir():
        raise DatasetError(f"{root} is not a folder holding a built dataset")
    have, want = checksums(root), manifest.checksums
    return Verification(missing=tuple(sorted(set(want) - set(have))), extra=tuple(sorted(set(have) - set(want))),
                        different=tuple(sorted(k for k in set(want) & set(have) if want[k] != have[k])),
                        checked=len(want))


# --------------------------------------------------------------------------------------------- build
def build(manifest: DatasetManifest, out: Path, *, workers: int = 1,
          progress: Callable[[str, int, int], None] | None = None, backend: Backend | None = None) -> dict[str, str]:
    """Collect every task of ``manifest`` into ``out`` (resumable), write its card and the build record; returns
    the built dataset's checksums. ``progress(task, successes, attempts)`` after each attempt. ``backend``
    (:class:`gendex.fanout.Backend`, default ``workers`` local processes) runs the attempts, in worker processes
    with pinned numerics (:mod:`gendex.data.numerics`: the same bytes on any x86-64 CPU); a Ray instance is started
    once for the whole build."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    record = {"manifest": manifest.name, "description": manifest.description, "gendex_version":
              manifest.gendex_version, "solver": manifest.solver, "tasks": []}
    if manifest.conventions != 1:  # the default is left out, so a published build record stays the same bytes
        record["conventions"] = manifest.conventions
    backend = numerics.pinned_backend(backend or Backend.from_options(workers))
    with session(backend):
        for t in manifest.tasks:
            _build_task(manifest, t, out, backend, progress, record)
    (out / BUILD_RECORD).write_text(json.dumps(record, indent=1) + "\n")
    return checksums(out)


def _build_task(manifest: DatasetManifest, t: DatasetTask, out: Path, backend: Backend,
                progress: Callable[[str, int, int], None] | None, record: dict) -> None:
    """Collect one task of ``manifest``, write its card, and add its line to the build ``record``."""
    from gendex.data.collector import CollectConfig, collect, write_card
    from gendex.solve import SOLVER_ENV_KWARGS, SOLVERS
    from gendex_envs.registry import resolve_task

    version = resolve_task(t.task)
    cfg = CollectConfig(task_id=version.env_id, num_success=t.episodes, out=out / manifest.folder(t),
                        formats=("lerobot",), cameras=manifest.cameras, seed=t.seed, max_attempts=t.max_attempts,
                        resolution=manifest.resolution, video_codec=manifest.video_codec,
                        conventions=manifest.conventions, **SOLVER_ENV_KWARGS[manifest.solver])
    state = collect(cfg, SOLVERS[manifest.solver],
                    None if progress is None else lambda s, name=t.task: progress(name, s.successes, s.attempts),
                    backend=backend)
    if state.successes < t.episodes:
        raise DatasetError(f"{t.task}: {state.successes} of {t.episodes} episodes after {state.attempts} "
                           f"attempts; raise max_attempts or fix the task (failures: {state.failures})")
    write_card(cfg, version.spec.instruction, manifest.solver, state)
    record["tasks"].append({"task": t.task, "episodes": t.episodes, "seed": t.seed, "attempts": state.attempts,
                            "env_steps": state.env_steps, "kept_seeds": state.kept_seeds,
                            "failures": dict(sorted(state.failures.items()))})


def record_checksums(manifest: DatasetManifest, sums: dict[str, str],
                     built_with: BuiltWith | None = None) -> DatasetManifest:
    """``manifest`` with its expected checksums replaced by ``sums`` and, when given, the code that built them
    (``gendex dataset build --record``)."""
    return replace(manifest, checksums=dict(sums), built_with=built_with or manifest.built_with)


def mark_stale(manifest: DatasetManifest) -> DatasetManifest:
    """``manifest`` marked as built by older code (``gendex dataset stale``): its checksums stay as the record of
    what was published, and builds say they will differ."""
    built = manifest.built_with or BuiltWith()
    return replace(manifest, built_with=replace(built, stale=True))


# --------------------------------------------------------------------------------------------- remotes
class Remote(Protocol):
    """Where built datasets are published: ``push`` a folder as ``repo_id``, ``pull`` it back into a folder."""

    def push(self, root: Path, repo_id: str, tags: tuple[str, ...]) -> str: ...

    def pull(self, repo_id: str, out: Path) -> Path: ...


class HubRemote:
    """The Hugging Face Hub through ``huggingface_hub``: a dataset repo (created if needed), the whole folder in one
    commit, and each tag put on that commit (a tag left by an earlier push is moved: lerobot loads a dataset at its
    ``v3.0`` tag, so a tag left behind would serve the old files). ``endpoint``/``token`` as ``HfApi`` takes them
    (default: the environment's)."""

    def __init__(self, endpoint: str | None = None, token: str | None = None, api=None):
        from huggingface_hub import HfApi

        self.api = api if api is not None else HfApi(endpoint=endpoint, token=token)

    def push(self, root: Path, repo_id: str, tags: tuple[str, ...]) -> str:
        self.api.create_repo(repo_id, repo_type="dataset", exist_ok=True)
        info = self.api.upload_folder(repo_id=repo_id, repo_type="dataset", folder_path=str(root),
                                      commit_message=f"GenDex dataset {repo_id}")
        revision = info.oid  # the commit just made (or, when nothing changed, the commit that holds these files)
        existing = {ref.name: ref.target_commit for ref in self.api.list_repo_refs(repo_id, repo_type="dataset").tags}
        for tag in tags:
            if existing.get(tag) == revision:
                continue
            if tag in existing:
                log.info("moving tag %s of %s from %s to %s", tag, repo_id, existing[tag], revision)
                self.api.delete_tag(repo_id, tag=tag, repo_type="dataset")
            self.api.create_tag(repo_id, tag=tag, revision=revision, repo_type="dataset")
        return str(info.commit_url)

    def pull(self, repo_id: str, out: Path) -> Path:
        """Download the repo's files at one revision, after its listing passed :func:`check_listing` (so an
        oversized repo is refused before any byte of it is fetched, and the files fetched are the ones listed)."""
        info = self.api.dataset_info(repo_id, files_metadata=True)
        if info.siblings is None:
            raise DatasetError(f"the Hub did not list the files of {repo_id}; a pull checks their number and sizes "
                               "before downloading")
        check_listing([(s.rfilename, s.size) for s in info.siblings])
        return Path(self.api.snapshot_download(repo_id=repo_id, repo_type="dataset", revision=info.sha,
                                               local_dir=str(out)))


class FolderRemote:
    """A folder standing in for the Hub: ``<folder>/<org>/<name>/`` holds the files of the last push and a ``.tags``
    file, JSON mapping each tag to the revision it is on. A revision is the SHA-256 of the pushed files' paths and
    checksums (:meth:`revision`), so, as on the Hub, a push of changed files makes a new revision and moves the tags
    to it, and a push of the same files keeps both."""

    def __init__(self, folder: Path):
        self.folder = Path(folder)

    def _repo(self, repo_id: str) -> Path:
        if repo_id.count("/") != 1 or not all(repo_id.split("/")):
            raise DatasetError(f"repo id {repo_id!r} must be ORG/NAME")
        return self.folder / repo_id

    def push(self, root: Path, repo_id: str, tags: tuple[str, ...]) -> str:
        dest = self._repo(repo_id)
        old = self.tags(repo_id)
        with atomic_dir(dest, replace=True) as tmp:
            shutil.copytree(root, tmp, dirs_exist_ok=True)
            revision = _revision(tmp)
            (tmp / ".tags").write_text(json.dumps(old | dict.fromkeys(tags, revision), indent=1, sort_keys=True) + "\n")
        return str(dest)

    def tags(self, repo_id: str) -> dict[str, str]:
        """Tag -> the revision it is on (empty for a repo not pushed yet)."""
        path = self._repo(repo_id) / ".tags"
        if not path.is_file():
            return {}
        try:
            return dict(json.loads(path.read_text()))
        except ValueError:  # written before tags had revisions: a tag name a line, its revision unknown
            return dict.fromkeys(path.read_text().split(), "")

    def revision(self, repo_id: str) -> str:
        """The revision of the repo's files as they are now (its head)."""
        return _revision(self._repo(repo_id))

    def pull(self, repo_id: str, out: Path) -> Path:
        src = self._repo(repo_id)
        if not src.is_dir():
            raise DatasetError(f"{repo_id} is not on the remote {self.folder}")
        regular_files_only(src)  # a link is not followed, a pipe not read
        shutil.copytree(src, out, ignore=shutil.ignore_patterns(".tags"), dirs_exist_ok=True, symlinks=True)
        return Path(out)


def _revision(folder: Path) -> str:
    """:class:`FolderRemote`'s revision id of the files in ``folder``: SHA-256 of their paths and checksums."""
    return hashlib.sha256(json.dumps(checksums(folder), sort_keys=True).encode()).hexdigest()


REPO_TAGS = ("v3.0",)
"""Git tags of a pushed repo: lerobot finds a dataset's format version by its tag (the v3.0 codebase version)."""


MAX_DOWNLOAD_DEPTH = 32
"""Folder levels a download may nest (a LeRobot dataset's deepest file, ``<task>/lerobot/videos/<key>/chunk-000/
file-000.mp4``, is 6 levels down). The copy recurses once per level: 500 levels raised a bare ``RecursionError``."""


MAX_DOWNLOAD_FILES = 500_000
"""Files and folders a download may hold, all together (folders count too: a flood of empty folders costs inodes
and time as files do). A task's LeRobot dataset holds 7 files in 7 folders, plus per camera 2 folders and one video
per episode: the published one-task datasets hold 8 to 11 files, ``gendex-lib-v1`` (86 tasks, 50 episodes, no
camera) about 1 200 entries, and 86 tasks of 200 episodes with 4 cameras about 71 000."""
MAX_DOWNLOAD_BYTES = 200_000_000_000
"""Bytes a download's files may hold, all together (each file's size as listed or as ``lstat`` gives it, so a sparse
file counts at its full length, the bytes a copy would write). ``gendex-smoke`` is 0.36 MB; a task's state data is
about 60 kB an episode and a 64 px AV1 video about 23 kB an episode and camera, so ``gendex-lib-v1`` is about
0.26 GB, and 86 tasks of 200 episodes with 4 cameras at 256 px (about 0.4 MB a video) about 29 GB."""


def _too_many(count: int, where: str) -> DatasetError:
    return DatasetError(f"the download holds more than MAX_DOWNLOAD_FILES = {MAX_DOWNLOAD_FILES} files and folders "
                        f"(entry {count}: {quote(where)}); a dataset holds about 14 per task and one video per "
                        "episode and camera")


def _too_big(total: int, where: str) -> DatasetError:
    return DatasetError(f"the download's files hold more than MAX_DOWNLOAD_BYTES = {MAX_DOWNLOAD_BYTES} bytes "
                        f"({total} with {quote(where)}); a dataset's state data is about 60 kB an episode, a video "
                        "tens to hundreds of kB")


def check_listing(files: list[tuple[str, int | None]]) -> None:
    """Refuse (:class:`DatasetError`) a remote's listing of ``(path, size)`` that would exceed
    :data:`MAX_DOWNLOAD_FILES` (files and the folders their paths imply), :data:`MAX_DOWNLOAD_BYTES` or
    :data:`MAX_DOWNLOAD_DEPTH`, or that does not say a file's size: checked before anything is downloaded."""
    folders: set[str] = set()
    total = 0
    for count, (name, size) in enumerate(files, start=1):
        parts = name.split("/")
        if len(parts) - 1 > MAX_DOWNLOAD_DEPTH:
            raise DatasetError(f"{quote(name)} is nested more than MAX_DOWNLOAD_DEPTH = {MAX_DOWNLOAD_DEPTH} folders "
                               "deep; a dataset's files lie a few levels down")
        folders.update("/".join(parts[:i]) for i in range(1, len(parts)))
        if count + len(folders) > MAX_DOWNLOAD_FILES:
            raise _too_many(count + len(folders), name)
        if not isinstance(size, int) or isinstance(size, bool) or size < 0:
            raise DatasetError(f"the remote lists {quote(name)} without a size ({quote(size)}); every file's size "
                               "must be known before the download, to keep it within MAX_DOWNLOAD_BYTES")
        total += size
        if total > MAX_DOWNLOAD_BYTES:
            raise _too_big(total, name)


def regular_files_only(root: Path) -> None:
    """Refuse (:class:`DatasetError` naming the entry) a symbolic link or a non-regular file anywhere under ``root``,
    folders nested deeper than :data:`MAX_DOWNLOAD_DEPTH`, more than :data:`MAX_DOWNLOAD_FILES` files and folders,
    or files holding more than :data:`MAX_DOWNLOAD_BYTES` together; links are not followed. The walk keeps its own
    stack, so no depth of nesting makes it recurse, and stops at the first entry over a limit."""
    root = Path(root)
    stack = [(root, 0)]
    count = total = 0
    while stack:
        folder, depth = stack.pop()
        with os.scandir(folder) as entries:
            for entry in entries:
                path = Path(entry.path)
                info = entry.stat(follow_symlinks=False)
                mode = info.st_mode
                count += 1
                if count > MAX_DOWNLOAD_FILES:
                    raise _too_many(count, str(path.relative_to(root)))
                if stat.S_ISLNK(mode):
                    raise DatasetError(f"{path.relative_to(root)} is a symbolic link: a dataset may hold only regular "
                                       "files and folders")
                if stat.S_ISDIR(mode):
                    if depth + 1 > MAX_DOWNLOAD_DEPTH:
                        raise DatasetError(f"{quote(str(path.relative_to(root)))} is nested more than "
                                           f"MAX_DOWNLOAD_DEPTH = {MAX_DOWNLOAD_DEPTH} folders deep; a dataset's "
                                           "files lie a few levels down")
                    stack.append((path, depth + 1))
                elif not stat.S_ISREG(mode):
                    raise DatasetError(f"{path.relative_to(root)} is not a regular file or folder: a dataset may hold "
                                       "only regular files and folders")
                else:
                    total += info.st_size
                    if total > MAX_DOWNLOAD_BYTES:
                        raise _too_big(total, str(path.relative_to(root)))


class _CopyBudget:
    """A ``copytree`` copy function that counts what it copies (files; bytes, each file's size before and after the
    copy, whichever is larger) against :data:`MAX_DOWNLOAD_FILES` and :data:`MAX_DOWNLOAD_BYTES`, refusing a file
    that would pass a limit before copying it: a download that changed after :func:`regular_files_only` saw it is
    still stopped, and the caller removes the partial copy."""

    def __init__(self) -> None:
        self.count = self.total = 0

    def __call__(self, src: str, dst: str) -> str:
        self.count += 1
        if self.count > MAX_DOWNLOAD_FILES:
            raise _too_many(self.count, os.path.basename(src))
        size = os.lstat(src).st_size
        if self.total + size > MAX_DOWNLOAD_BYTES:
            raise _too_big(self.total + size, os.path.basename(src))
        shutil.copy2(src, dst, follow_symlinks=False)
        self.total += max(size, os.lstat(dst).st_size)
        if self.total > MAX_DOWNLOAD_BYTES:
            raise _too_big(self.total, os.path.basename(src))
        return dst


def _inside(root: Path, *parts: str) -> Path:
    """``root / parts``, refused unless it resolves inside ``root``."""
    path = Path(root).joinpath(*parts)
    if not path.resolve().is_relative_to(Path(root).resolve()):
        raise DatasetError(f"{quote('/'.join(parts))} leads outside {root}")
    return path


def _tasks_of(root: Path) -> list[str]:
    """The task folders a build record names: each a versioned GenDex id's name part (checked; module doc)."""
    rec = Path(root) / BUILD_RECORD
    if rec.is_symlink() or not rec.is_file():
        raise DatasetError(f"{root} holds no {BUILD_RECORD}: build it with `gendex dataset build` first")
    size = rec.stat().st_size
    if size > MAX_BUILD_RECORD_BYTES:
        raise DatasetError(f"{BUILD_RECORD}: {size} bytes; at most MAX_BUILD_RECORD_BYTES = {MAX_BUILD_RECORD_BYTES} "
                           "are allowed")
    try:
        record = parse_json_bounded(rec.read_bytes(), BUILD_RECORD, max_bytes=MAX_BUILD_RECORD_BYTES,
                                    max_nodes=MAX_BUILD_RECORD_NODES)
    except ValueError as exc:
        raise DatasetError(f"{BUILD_RECORD}: not a readable build record ({exc})") from None
    tasks = record.get("tasks") if isinstance(record, dict) else None
    if not isinstance(tasks, list) or not tasks:
        raise DatasetError(f"{BUILD_RECORD}: `tasks` must be a non-empty list")
    names: list[str] = []
    for i, t in enumerate(tasks):
        task = t.get("task") if isinstance(t, dict) else None
        m = TASK_ID.fullmatch(task) if isinstance(task, str) else None
        if m is None:
            raise DatasetError(f"{BUILD_RECORD}: tasks[{i}].task {quote(task)} is not a versioned GenDex task id "
                               "(GenDex/<Name>-v<N>, Name CamelCase letters and digits)")
        if m.group(1) in names:
            raise DatasetError(f"{BUILD_RECORD}: tasks[{i}].task {quote(task)} is listed twice")
        names.append(m.group(1))
    return names


def _to_repo(root: Path, staging: Path) -> None:
    """The repo's layout of a build: one task's LeRobot dataset at the repo root (so ``LeRobotDataset(repo_id)``
    loads it), several tasks in ``<task>/`` folders; the build record at the root; no bookkeeping."""
    tasks = _tasks_of(root)
    ignore = shutil.ignore_patterns(*SKIPPED, ".*")
    if len(tasks) == 1:
        shutil.copytree(Path(root) / tasks[0] / "lerobot", staging, ignore=ignore)
    else:
        for t in tasks:
            shutil.copytree(Path(root) / t / "lerobot", staging / t / "lerobot", ignore=ignore)
    shutil.copy2(Path(root) / BUILD_RECORD, staging / BUILD_RECORD)


def _from_repo(staging: Path, out: Path) -> None:
    """Back from the repo's layout (:func:`_to_repo`) to a build's, so the copy verifies against the manifest.
    ``staging`` must have passed :func:`regular_files_only`; every task name is checked by :func:`_tasks_of`."""
    tasks = _tasks_of(staging)
    out.mkdir(parents=True, exist_ok=True)
    budget = _CopyBudget()
    if len(tasks) == 1:
        dest = _inside(out, tasks[0], "lerobot")
        shutil.copytree(staging, dest, ignore=shutil.ignore_patterns(BUILD_RECORD, ".*"), dirs_exist_ok=True,
                        copy_function=budget)
    else:
        for t in tasks:
            src = _inside(staging, t)
            if not src.is_dir():
                raise DatasetError(f"the repo has no folder {t}/ for a task its {BUILD_RECORD} names")
            shutil.copytree(src, _inside(out, t), dirs_exist_ok=True, copy_function=budget)
    budget(str(staging / BUILD_RECORD), str(out / BUILD_RECORD))


def _move_into(work: Path, out: Path) -> None:
    """Move the complete copy ``work`` to ``out`` (renamed when ``out`` does not exist; else file by file, next to
    what ``out`` holds already)."""
    if not out.exists():
        work.rename(out)
        return
    if not out.is_dir() or out.is_symlink():
        raise DatasetError(f"--out {out} exists and is not a folder")
    for path in sorted(work.rglob("*")):
        if path.is_file():
            target = _inside(out, *path.relative_to(work).parts)
            target.parent.mkdir(parents=True, exist_ok=True)
            os.replace(path, target)


def push(root: Path, repo_id: str, remote: Remote, manifest: DatasetManifest | None = None) -> str:
    """Publish the built dataset at ``root`` as ``repo_id`` (verified against ``manifest`` first, when given)."""
    if manifest is not None and manifest.checksums:
        v = verify(root, manifest)
        if not v.ok:
            raise DatasetError(f"{root} does not match manifest {manifest.name!r}: {v.summary()}; not pushed")
    with tempfile.TemporaryDirectory(prefix="gendex-push-") as tmp:
        staging = Path(tmp) / "repo"
        _to_repo(Path(root), staging)
        return remote.push(staging, repo_id, REPO_TAGS)


def pull(repo_id: str, out: Path, remote: Remote, manifest: DatasetManifest | None = None) -> Verification | None:
    """Download ``repo_id`` into ``out`` (a build's layout) and verify it against ``manifest`` (when given)."""
    out = Path(out)
    with tempfile.TemporaryDirectory(prefix="gendex-pull-") as tmp:
        staging = remote.pull(repo_id, Path(tmp) / "repo")
        regular_files_only(staging)
        _tasks_of(staging)  # every name checked before anything is written
        out.parent.mkdir(parents=True, exist_ok=True)
        work = Path(tempfile.mkdtemp(prefix=f".{out.name}.pull-", dir=out.parent))
        try:
            _from_repo(staging, work)
            _move_into(work, out)
        finally:
            shutil.rmtree(work, ignore_errors=True)
    return verify(out, manifest) if manifest is not None else None


__all__ = ["BUILD_RECORD", "DATASETS_DIR", "MAX_BUILD_RECORD_BYTES", "MAX_DOWNLOAD_BYTES", "MAX_DOWNLOAD_FILES",
           "DatasetError", "DatasetManifest", "DatasetTask", "FolderRemote", "HubRemote", "Remote", "Verification",
           "build", "check_listing", "checksums", "load_manifest", "pull", "push", "record_checksums",
           "regular_files_only", "save_manifest", "verify"]
