"""The task store: data files of task versions kept once by content, beside the code and spec that stay in each folder.

A task root holds its versions (``<Name>/v<N>/``) and one object store, ``<root>/.objects/<ab>/<sha256>``: files
named by the SHA-256 of their bytes, so a file that many versions hold (a rewording's transcript, renders and
generation records are its source's) is stored once. A version folder keeps inline what people review and what
runs as code (:func:`is_inline`: the spec, every ``.py`` file, and the records that belong to this version alone:
its gate measurement, rewording or promotion record); every other file (transcripts, renders, generation records,
start states, trained policies) may live in the store, listed in the folder's ``tree.json``::

    {"format": 1, "files": {"<path in the version>": {"sha256": "…", "bytes": 81234}, …}}

:class:`~gendex_envs.task_version.TaskVersion` resolves every read through :meth:`TaskLayout.resolve
<gendex_envs.task_version.TaskLayout.resolve>` (a file in the folder wins over a tree entry), so every reader sees a
whole version, and :meth:`~gendex_envs.task_version.TaskVersion.file_digest` of a packed version equals that of the
whole folder it was packed from (:func:`pack` checks it and undoes itself otherwise). The heavy artefacts that no env
needs are then out of the version folders that registration and env building touch, still checksummed: the object's
name is its SHA-256, checked whenever a version's digest is taken and by :func:`verify` (``gendex store verify``).

A tree is untrusted data like the rest of a folder on ``$GENDEX_TASKS_PATH``: its paths are relative, plain and may
not name code or the spec (a tree cannot supply what the static check and the trust record vet), and objects are
looked up only under the root's own store. Write paths (``TaskLayout.policy`` …) never resolve into the store, so a
writer cannot change a shared object.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import re
import shutil
import stat
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path, PurePosixPath

from gendex_envs.errors import TaskSpecError

log = logging.getLogger(__name__)

OBJECTS = ".objects"
"""The object store's folder inside a task root."""
TREE_NAME = "tree.json"
FORMAT = 1


@lru_cache(maxsize=1)
def inline_names() -> frozenset[str]:
    """Files (by path in the version folder) that always stay in the folder, besides every ``.py`` file: the spec,
    ``tree.json`` and the records of this version alone (its gate measurement, rewording, revision or promotion)."""
    from gendex_envs.task_version import TaskLayout

    layout = TaskLayout(".")
    return frozenset({layout.spec.name, TREE_NAME, *(layout.record(k).name for k in ("solvability", "reword",
                                                                                         "revision", "promotion"))})
MAX_TREE_BYTES = 16 << 20
MAX_TREE_FILES = 100_000
MAX_OBJECT_BYTES = 1 << 32
_PART = re.compile(r"\A[A-Za-z0-9_][A-Za-z0-9_.\-]{0,127}\Z")
_SHA = re.compile(r"\A[0-9a-f]{64}\Z")


class StoreError(TaskSpecError):
    """A tree that cannot be read, an object missing or whose bytes do not match its name."""


@dataclass(frozen=True)
class TreeEntry:
    sha256: str
    bytes: int


def is_inline(rel: str) -> bool:
    """Whether the file at ``rel`` (a posix path in a version folder) always stays in the folder."""
    return rel in inline_names() or rel.endswith(".py") or "__pycache__" in rel.split("/")


def object_path(tasks_root: Path, sha256: str) -> Path:
    return tasks_root / OBJECTS / sha256[:2] / sha256


def _check_rel(rel: object, where: Path) -> str:
    if not isinstance(rel, str):
        raise StoreError(f"{where}: a file path is not a string")
    parts = PurePosixPath(rel).parts
    if not parts or PurePosixPath(rel).as_posix() != rel or any(not _PART.fullmatch(p) for p in parts) or \
            len(parts) > 8:
        raise StoreError(f"{where}: file path {rel[:120]!r} is not a plain relative path (parts of letters, digits, "
                         "'_', '.', '-', not starting with '.', at most 8)")
    if is_inline(rel):
        raise StoreError(f"{where}: {rel!r} may not come from the store: the spec, code and the version's own "
                         f"records stay in the folder ({', '.join(sorted(inline_names()))}, *.py)")
    return rel


def _parse_tree(path: Path) -> dict[str, TreeEntry]:
    st = os.lstat(path)
    if not stat.S_ISREG(st.st_mode):
        raise StoreError(f"{path}: not a regular file")
    if st.st_size > MAX_TREE_BYTES:
        raise StoreError(f"{path}: {st.st_size} bytes, more than MAX_TREE_BYTES = {MAX_TREE_BYTES}")
    try:
        data = json.loads(path.read_bytes())
    except (ValueError, RecursionError) as exc:
        raise StoreError(f"{path}: not JSON ({exc})") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT or not isinstance(data.get("files"), dict):
        raise StoreError(f"{path}: not a format-{FORMAT} tree (an object with 'format': {FORMAT} and 'files')")
    if len(data["files"]) > MAX_TREE_FILES:
        raise StoreError(f"{path}: more than MAX_TREE_FILES = {MAX_TREE_FILES} files")
    out = {}
    for rel, entry in data["files"].items():
        _check_rel(rel, path)
        if not isinstance(entry, dict) or set(entry) != {"sha256", "bytes"}:
            raise StoreError(f"{path}: entry {rel!r} holds exactly sha256 and bytes")
        sha, size = entry["sha256"], entry["bytes"]
        if not isinstance(sha, str) or not _SHA.fullmatch(sha):
            raise StoreError(f"{path}: entry {rel!r}: sha256 is not 64 lower-case hex digits")
        if type(size) is not int or not 0 <= size <= MAX_OBJECT_BYTES:
            raise StoreError(f"{path}: entry {rel!r}: bytes {size!r} is not an integer in [0, {MAX_OBJECT_BYTES}]")
        out[rel] = TreeEntry(sha, size)
    return out


@lru_cache(maxsize=4096)
def _tree_cached(path: str, signature: tuple[int, int, int]) -> dict[str, TreeEntry]:
    return _parse_tree(Path(path))


def load_tree(folder: str | Path) -> dict[str, TreeEntry]:
    """The tree of a version folder (empty when it has none); :class:`StoreError` for one that is not valid."""
    path = Path(folder) / TREE_NAME
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return {}
    return dict(_tree_cached(str(path), (st.st_mtime_ns, st.st_size, st.st_ino)))


def resolve(folder: Path, rel: str) -> Path:
    """Where the file ``rel`` of the version in ``folder`` lies: the folder's own file when present, else its store
    object when the tree lists it, else the (missing) path in the folder."""
    own = folder / rel
    if os.path.lexists(own) or is_inline(rel):
        return own
    entry = load_tree(folder).get(rel)
    return object_path(folder.parent.parent, entry.sha256) if entry is not None else own


def listing(folder: Path, sub: str, suffix: str) -> dict[str, Path]:
    """Files ``<sub>/<stem><suffix>`` of the version (own and stored): stem -> resolved path, sorted by stem."""
    found: dict[str, Path] = {}
    prefix = f"{sub}/"
    for rel, entry in load_tree(folder).items():
        if rel.startswith(prefix) and "/" not in rel[len(prefix):] and rel.endswith(suffix):
            found[rel[len(prefix):-len(suffix)]] = object_path(folder.parent.parent, entry.sha256)
    own = folder / sub
    if own.is_dir():
        # every entry, not only regular files: a link or a FIFO is listed, for the reader's own checks to refuse
        found.update({p.name[:-len(suffix)]: p for p in own.iterdir() if p.name.endswith(suffix)})
    return dict(sorted(found.items()))


def files(folder: Path) -> list[tuple[str, Path, str | None]]:
    """Every file of the whole version: (relative path, where it lies, the SHA-256 its bytes must have or None for
    a file in the folder), sorted by path parts. Left out: ``tree.json`` and ``__pycache__`` folders. A symbolic link
    or other non-regular entry in the folder is listed as itself (never followed)."""
    entries: dict[str, tuple[Path, str | None]] = {}
    for rel, entry in load_tree(folder).items():
        entries[rel] = (object_path(folder.parent.parent, entry.sha256), entry.sha256)
    for top, dirs, names in os.walk(folder, followlinks=False):
        dirs[:] = [d for d in dirs if d != "__pycache__"]
        here = Path(top)
        for n in names + [d for d in dirs if (here / d).is_symlink()]:
            rel = (here / n).relative_to(folder).as_posix()
            if rel != TREE_NAME:
                entries[rel] = (here / n, None)
    return [(rel, *entries[rel]) for rel in sorted(entries, key=lambda r: PurePosixPath(r).parts)]


def read_object(path: Path, sha256: str) -> bytes:
    """An object's bytes, checked against its name; :class:`StoreError` when missing, a link, or different."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
    except OSError as exc:
        raise StoreError(f"stored file {path} cannot be read ({exc.strerror}); the store of {path.parent.parent.parent}"
                         " is incomplete: restore it (git checkout) or re-pack the version") from None
    with os.fdopen(fd, "rb") as fh:
        data = fh.read(MAX_OBJECT_BYTES + 1)
    if hashlib.sha256(data).hexdigest() != sha256:
        raise StoreError(f"stored file {path} does not match its SHA-256 name: the store was changed")
    return data


# ------------------------------------------------------------------------------------------------ writing
def _store(tasks_root: Path, data: bytes) -> TreeEntry:
    from gendex_envs.atomic_io import write_bytes

    sha = hashlib.sha256(data).hexdigest()
    target = object_path(tasks_root, sha)
    if not (target.is_file() and hashlib.sha256(target.read_bytes()).hexdigest() == sha):
        target.parent.mkdir(parents=True, exist_ok=True)
        write_bytes(target, data)
    return TreeEntry(sha, len(data))


def write_tree(folder: Path, tree: dict[str, TreeEntry]) -> Path | None:
    from gendex_envs.atomic_io import write_text

    path = folder / TREE_NAME
    if not tree:
        path.unlink(missing_ok=True)
        return None
    body = {"format": FORMAT, "files": {rel: {"sha256": e.sha256, "bytes": e.bytes} for rel, e in sorted(tree.items())}}
    return write_text(path, json.dumps(body, indent=1, sort_keys=True) + "\n")


@dataclass(frozen=True)
class PackResult:
    folder: Path
    moved: int
    """Files moved from the folder into the store."""
    bytes_moved: int


def pack(folder: str | Path) -> PackResult:
    """Move every file of the version in ``folder`` (a version folder, or a draft of one under ``<root>/.drafts/``)
    that need not be inline (:func:`is_inline`) into its root's store and list it in ``tree.json``. The version's
    :meth:`~gendex_envs.task_version.TaskVersion.file_digest` is the same after; when it is not (it cannot be, short
    of a concurrent writer), the moved files are put back and :class:`StoreError` is raised."""
    from gendex_envs.task_version import TaskVersion

    folder = Path(folder)
    before = TaskVersion(root=folder, name=folder.parent.name, version=0).file_digest()
    tasks_root = folder.parent.parent
    tree = load_tree(folder)
    moved: list[tuple[str, Path]] = []
    for top, dirs, names in os.walk(folder, followlinks=False):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__")
        for n in sorted(names):
            path = Path(top) / n
            rel = path.relative_to(folder).as_posix()
            if is_inline(rel) or not stat.S_ISREG(os.lstat(path).st_mode):
                continue
            _check_rel(rel, folder)
            tree[rel] = _store(tasks_root, path.read_bytes())
            moved.append((rel, path))
    if not moved:
        return PackResult(folder, 0, 0)
    old_tree = (folder / TREE_NAME).read_bytes() if (folder / TREE_NAME).is_file() else None
    write_tree(folder, tree)
    for _, path in moved:
        path.unlink()
    after = TaskVersion(root=folder, name=folder.parent.name, version=0).file_digest()
    if after != before:
        for rel, path in moved:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(object_path(tasks_root, tree[rel].sha256).read_bytes())
        if old_tree is None:
            (folder / TREE_NAME).unlink()
        else:
            (folder / TREE_NAME).write_bytes(old_tree)
        raise StoreError(f"packing {folder} changed its digest ({before[:12]} -> {after[:12]}); nothing was moved")
    _prune_empty(folder)
    return PackResult(folder, len(moved), sum(tree[rel].bytes for rel, _ in moved))


def _prune_empty(folder: Path) -> None:
    for top, _dirs, _names in os.walk(folder, topdown=False):
        if Path(top) != folder and not any(Path(top).iterdir()):
            Path(top).rmdir()


def unpack(folder: str | Path) -> int:
    """Copy every stored file of the version back into its folder and drop ``tree.json`` (a whole folder again, to
    hand to someone without the store); returns how many files."""
    folder = Path(folder)
    tree = load_tree(folder)
    for rel, entry in tree.items():
        target = folder / rel
        if not os.path.lexists(target):
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(read_object(object_path(folder.parent.parent, entry.sha256), entry.sha256))
    (folder / TREE_NAME).unlink(missing_ok=True)
    return len(tree)


def export(folder: str | Path, out: str | Path, skip: tuple[str, ...] = ("__pycache__",)) -> Path:
    """Write the whole version in ``folder`` as a plain folder ``out`` (its own files and its stored files, checked
    against their names; no ``tree.json``): a copy that needs no store, to place under another task root."""
    folder, out = Path(folder), Path(out)
    tree = load_tree(folder)
    shutil.copytree(folder, out, ignore=shutil.ignore_patterns(TREE_NAME, *skip))
    for rel, entry in tree.items():
        target = out / rel
        if not os.path.lexists(target):
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(read_object(object_path(folder.parent.parent, entry.sha256), entry.sha256))
    return out


def verify(tasks_root: str | Path) -> list[str]:
    """Problems of a root's store: a tree that does not load, an object missing or whose bytes differ from its
    name, an object no tree lists (left by a removed version: ``gendex store pack --prune`` removes it)."""
    from gendex_envs.task_version import versions_in

    root = Path(tasks_root)
    problems: list[str] = []
    used: set[str] = set()
    for version in versions_in(root):
        try:
            tree = load_tree(version.root)
        except StoreError as exc:
            problems.append(str(exc))
            continue
        for rel, entry in tree.items():
            used.add(entry.sha256)
            path = object_path(root, entry.sha256)
            if not path.is_file():
                problems.append(f"{version.env_id}: {rel} is stored as {entry.sha256[:12]}…, which is missing")
            elif path.stat().st_size != entry.bytes:
                problems.append(f"{version.env_id}: {rel}: {path.stat().st_size} bytes stored, the tree says "
                                f"{entry.bytes}")
    store = root / OBJECTS
    if store.is_dir():
        for path in sorted(store.glob("*/*")):
            if path.name not in used:
                problems.append(f"{path.relative_to(root)}: no version lists it")
            elif hashlib.sha256(path.read_bytes()).hexdigest() != path.name or path.parent.name != path.name[:2]:
                problems.append(f"{path.relative_to(root)}: its bytes do not match its name")
    return problems


def prune(tasks_root: str | Path) -> int:
    """Remove objects that no version's tree lists; returns how many."""
    from gendex_envs.task_version import versions_in

    root = Path(tasks_root)
    used = {e.sha256 for v in versions_in(root) for e in load_tree(v.root).values()}
    removed = 0
    for path in sorted((root / OBJECTS).glob("*/*")) if (root / OBJECTS).is_dir() else []:
        if path.name not in used:
            path.unlink()
            removed += 1
    for d in (root / OBJECTS).glob("*") if (root / OBJECTS).is_dir() else []:
        if d.is_dir() and not any(d.iterdir()):
            d.rmdir()
    return removed


def unpacked_files(tasks_root: str | Path) -> list[str]:
    """Data files still in version folders (``<Name>/v<N>/<rel>`` under the root) that :func:`pack` would move."""
    from gendex_envs.task_version import versions_in

    root = Path(tasks_root)
    out = []
    for version in versions_in(root):
        for rel, path, sha in files(version.root):
            if sha is None and not is_inline(rel) and stat.S_ISREG(os.lstat(path).st_mode):
                out.append(path.relative_to(root).as_posix())
    return out


def store_bytes(tasks_root: str | Path) -> int:
    store = Path(tasks_root) / OBJECTS
    return sum(p.stat().st_size for p in store.glob("*/*")) if store.is_dir() else 0


__all__ = ["OBJECTS", "TREE_NAME", "PackResult", "StoreError", "TreeEntry", "export", "files", "is_inline", "listing",
           "load_tree", "object_path", "pack", "prune", "read_object", "resolve", "unpack", "unpacked_files", "verify"]
