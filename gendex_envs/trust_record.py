"""The trust record: which code files of the repository's task folder are trusted, by their bytes.

Code written by a model is untrusted wherever it runs; the committed library is trusted because people reviewed and
committed it. A file's place is not that review: ``gendex generate`` writes new reward code into ``generated_tasks/``
by default. So a reward module under the repository's task folder (:data:`~gendex_envs.registry.REPO_TASKS_DIR`) is
trusted only when its current bytes hash to the digest :data:`RECORD_NAME` records for its path; any other file
there (a new task, a changed module, a draft) is untrusted like a downloaded folder: the static check, the runtime
guard and the confined worker (:func:`gendex_envs.reward_module.load_reward_module`).

The record is ``generated_tasks/TRUSTED.sha256`` in ``sha256sum``'s format, one line per code file, sorted by path:
the SHA-256 of the file's bytes in lower-case hex, two spaces, and the path relative to ``generated_tasks/`` with
``/`` (``cd generated_tasks && sha256sum -c TRUSTED.sha256`` checks it). It is read once per process (at most
:data:`MAX_RECORD_BYTES`, parsed strictly: a line that is not exactly that, a path that is not a plain relative
``.py`` path, a duplicate path, a record that is a link); a malformed or missing record trusts nothing and says why
in the log. Files are hashed lazily, when a module is loaded, and the digest is cached by the file's
``(device, inode, mtime_ns, ctime_ns, size)`` (not for a file changed in the last :data:`RACY_NS`).

Only a person adds to it, deliberately, after reviewing a task: ``gendex trust generated_tasks/<Name>/v<N>``
(:func:`record_trusted`). ``gendex generate``, ``gendex promote`` and rewording never do. ``gendex trust --check``
(:func:`trust_status`) lists what differs, and a test holds the record equal to the committed code files.
"""

from __future__ import annotations

import hashlib
import logging
import os
import re
import stat
import threading
import time
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from gendex_envs.errors import GenDexError

log = logging.getLogger(__name__)

RECORD_NAME = "TRUSTED.sha256"
"""The record's file name, in the repository's task folder."""
MAX_RECORD_BYTES = 8_000_000
"""The record is never read past this (528 entries take 58 kB; this is about 70 000)."""
MAX_CODE_BYTES = 1_000_000
"""A larger file is not hashed, so not trusted (reward modules are refused past about 400 kB anyway)."""
CODE_SUFFIX = ".py"
RACY_NS = 2_000_000_000
"""A digest is cached only for a file last changed longer ago than this: file systems stamp times at a coarse tick
(a few ms), so a file rewritten with the same size right after it was hashed can keep its times ("racy git")."""
_PART = r"[A-Za-z0-9_][A-Za-z0-9_.-]*"
_LINE = re.compile(rf"([0-9a-f]{{64}})  ((?:{_PART}/)*{_PART}\.py)")
"""One line of the record: a digest, two spaces, a relative path whose parts start with a letter, digit or ``_``
(no ``..``, no hidden folder such as ``.drafts``, no absolute path, no backslash)."""
UPDATE_COMMAND = "gendex trust generated_tasks/<Name>/v<N>"


class TrustRecordError(GenDexError, ValueError):
    """The trust record cannot be read or written as asked (malformed, a link, a path outside the task folder)."""


# ---------------------------------------------------------------------------------------------- the format
def parse_record(data: bytes, source: str = RECORD_NAME) -> dict[str, str]:
    """Relative path -> digest of a record's bytes; :class:`TrustRecordError` naming the line and what is wrong."""
    if len(data) > MAX_RECORD_BYTES:
        raise TrustRecordError(f"{source}: more than {MAX_RECORD_BYTES} bytes")
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError as exc:
        raise TrustRecordError(f"{source}: byte {exc.start} is not ASCII") from None
    if text and not text.endswith("\n"):
        raise TrustRecordError(f"{source}: the last line does not end with a newline")
    entries: dict[str, str] = {}
    for number, line in enumerate(text.split("\n")[:-1], start=1):
        match = _LINE.fullmatch(line)
        if match is None:
            raise TrustRecordError(f"{source}: line {number} is not '<sha256 in lower-case hex>  <relative path "
                                   f"of a .py file>': {line[:120]!r}")
        digest, rel = match.groups()
        if rel in entries:
            raise TrustRecordError(f"{source}: line {number}: {rel} is recorded twice")
        entries[rel] = digest
    return entries


def render_record(entries: dict[str, str]) -> str:
    """The record's text for ``entries`` (path -> digest): sorted by path, ``sha256sum``'s format."""
    for rel in entries:
        if _LINE.fullmatch(f"{entries[rel]}  {rel}") is None:
            raise TrustRecordError(f"cannot record {rel!r} with digest {entries[rel]!r}: not a plain relative path "
                                   "of a .py file and a SHA-256")
    return "".join(f"{entries[rel]}  {rel}\n" for rel in sorted(entries))


def file_digest(path: str | Path) -> str | None:
    """SHA-256 of the regular file ``path`` (not followed if it is a link), or None when it is not one or is larger
    than :data:`MAX_CODE_BYTES`."""
    digest, _ = _hash(str(path))
    return digest


def _hash(path: str) -> tuple[str | None, tuple | None]:
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0))
    except OSError:
        return None, None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or st.st_size > MAX_CODE_BYTES:
            return None, None
        with os.fdopen(fd, "rb", closefd=False) as f:
            data = f.read(MAX_CODE_BYTES + 1)
        if len(data) > MAX_CODE_BYTES:
            return None, None
        return hashlib.sha256(data).hexdigest(), _key(st)
    finally:
        os.close(fd)


def _key(st: os.stat_result) -> tuple:
    return st.st_dev, st.st_ino, st.st_mtime_ns, st.st_ctime_ns, st.st_size


# ---------------------------------------------------------------------------------------------- the record, read once
@dataclass
class _Record:
    entries: dict[str, str] | None
    """Path -> digest; None when the record is missing or malformed (nothing trusted)."""
    digests: dict[str, tuple[tuple, str]] = field(default_factory=dict)
    """Path -> (the file's stat key, its digest) of files hashed so far."""


_records: dict[str, _Record] = {}
_lock = threading.Lock()


def tasks_dir() -> Path:
    """The repository's task folder (looked up each time: tests point it elsewhere)."""
    from gendex_envs import registry

    return registry.REPO_TASKS_DIR


def record_path(root: str | Path | None = None) -> Path:
    return Path(tasks_dir() if root is None else root) / RECORD_NAME


def read_record(root: str | Path | None = None) -> dict[str, str]:
    """The record of ``root`` (default: the repository's task folder), read now, strictly; raises
    :class:`TrustRecordError` (malformed, a link, not a file) or :class:`FileNotFoundError` (none)."""
    path = record_path(root)
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0))
    except FileNotFoundError:
        raise
    except OSError as exc:
        raise TrustRecordError(f"{path} cannot be read ({exc.strerror}; it may not be a link)") from None
    with os.fdopen(fd, "rb") as f:
        if not stat.S_ISREG(os.fstat(f.fileno()).st_mode):
            raise TrustRecordError(f"{path} is not a regular file")
        data = f.read(MAX_RECORD_BYTES + 1)
    return parse_record(data, str(path))


def _record(root: str) -> _Record:
    record = _records.get(root)
    if record is not None:
        return record
    with _lock:
        if root not in _records:
            try:
                entries: dict[str, str] | None = read_record(root)
            except FileNotFoundError:
                entries = None
                log.warning("no trust record %s: no reward module under %s is trusted; each goes through the static "
                            "check and the sandbox. Review the tasks and record them with `%s`", record_path(root),
                            root, UPDATE_COMMAND)
            except (TrustRecordError, OSError) as exc:
                entries = None
                log.error("the trust record is malformed, so no reward module under %s is trusted (each goes "
                          "through the static check and the sandbox): %s", root, exc)
            _records[root] = _Record(entries)
        return _records[root]


def forget() -> None:
    """Drop what this process read and hashed (after the record or the task folder's root changed)."""
    with _lock:
        _records.clear()


def is_recorded(root: str | Path, rel: str, data: bytes | None = None) -> bool:
    """Whether ``root/rel`` is trusted by ``root``'s record: a regular file (a folder: every ``.py`` file in it,
    at least one) whose bytes (``data`` when given: the bytes about to run) hash to the digest recorded for
    ``rel``. ``root`` is the task folder, resolved; ``rel`` a relative path, judged where it lies (not followed)."""
    root = str(Path(root))
    record = _record(root)
    if record.entries is None:
        return False
    rel = Path(rel).as_posix() if rel else ""
    path = os.path.join(root, rel) if rel else root
    if data is None:
        try:
            st = os.lstat(path)
        except OSError:
            return False
        if stat.S_ISDIR(st.st_mode):
            return _folder_recorded(root, rel)
        if not stat.S_ISREG(st.st_mode):
            return False
    expected = record.entries.get(rel)
    if expected is None:
        return False
    if data is not None:
        return hashlib.sha256(data).hexdigest() == expected
    cached = record.digests.get(rel)
    if cached is not None and cached[0] == _key(st):
        return cached[1] == expected
    digest, key = _hash(path)
    if digest is None:
        return False
    if time.time_ns() - max(key[2], key[3]) > RACY_NS:  # see RACY_NS
        record.digests[rel] = (key, digest)
    return digest == expected


def _folder_recorded(root: str, rel: str) -> bool:
    found = False
    for folder, dirs, files in os.walk(os.path.join(root, rel) if rel else root):
        dirs[:] = [d for d in dirs if d != "__pycache__"]
        for name in files:
            if name.endswith(CODE_SUFFIX):
                found = True
                sub = Path(folder, name).relative_to(root).as_posix()
                if not is_recorded(root, sub):
                    return False
    return found


# ---------------------------------------------------------------------------------------------- the human step
@dataclass(frozen=True)
class TrustStatus:
    """How the code files of the task folder compare with the record."""

    unrecorded: tuple[str, ...]
    """Code files the record does not list (untrusted)."""
    changed: tuple[str, ...]
    """Code files whose bytes differ from the recorded digest (untrusted)."""
    stale: tuple[str, ...]
    """Recorded paths with no such code file."""

    @property
    def clean(self) -> bool:
        return not (self.unrecorded or self.changed or self.stale)

    def lines(self) -> list[str]:
        return ([f"not recorded (untrusted): {p}" for p in self.unrecorded]
                + [f"changed since recorded (untrusted): {p}" for p in self.changed]
                + [f"recorded but missing: {p}" for p in self.stale])


@dataclass(frozen=True)
class TrustUpdate:
    """What :func:`record_trusted` wrote."""

    record: Path
    added: tuple[str, ...]
    changed: tuple[str, ...]
    unchanged: tuple[str, ...]
    dropped: tuple[str, ...]
    """Entries of files that no longer exist, left out of the new record."""


def code_files(root: str | Path | None = None) -> list[str]:
    """Every ``.py`` file under the task folder (not ``__pycache__``), relative, sorted: what could be loaded."""
    root = Path(tasks_dir() if root is None else root)
    found = []
    for folder, dirs, files in os.walk(root):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__")
        found += [Path(folder, n).relative_to(root).as_posix() for n in files if n.endswith(CODE_SUFFIX)]
    return sorted(found)


def trust_status(files: Iterable[str] | None = None, root: str | Path | None = None) -> TrustStatus:
    """Compare ``files`` (relative paths; default: :func:`code_files`) with the record, read now (a malformed one
    raises :class:`TrustRecordError`; a missing one is empty)."""
    root = Path(tasks_dir() if root is None else root)
    try:
        entries = read_record(root)
    except FileNotFoundError:
        entries = {}
    files = sorted(code_files(root) if files is None else files)
    unrecorded = tuple(f for f in files if f not in entries)
    changed = tuple(f for f in files if f in entries and file_digest(root / f) != entries[f])
    stale = tuple(sorted(set(entries) - set(files)))
    return TrustStatus(unrecorded, changed, stale)


def _inside(root: Path, path: Path) -> str:
    """``path`` relative to ``root`` (both absolute), judged where it lies: its folder resolved, its name not
    followed; :class:`TrustRecordError` when it is not inside."""
    named = path.absolute()
    lies = named.parent.resolve() / named.name if named.name not in ("", ".", "..") else named.resolve()
    try:
        rel = lies.relative_to(root)
    except ValueError:
        raise TrustRecordError(f"{path} is not in the repository's task folder {root}: the trust record covers only "
                               "it (trust another folder with trust_remote_code=True or GENDEX_TRUST_REMOTE_CODE=1)"
                               ) from None
    return rel.as_posix() if rel.parts else ""


def record_trusted(paths: Iterable[str | Path], root: str | Path | None = None) -> TrustUpdate:
    """Record the current bytes of the code files at ``paths`` as trusted: the deliberate step after a person
    reviewed them (``gendex trust``). Each path is a task version folder, a task folder (all its versions) or a
    ``.py`` file inside the task folder ``root`` (default: the repository's). Links are refused, not followed.
    Entries of files that no longer exist are dropped; the record is rewritten sorted, atomically. An existing record
    that is malformed raises :class:`TrustRecordError` (fix it first: nothing is guessed)."""
    from gendex_envs.atomic_io import atomic_path

    root = Path(tasks_dir() if root is None else root).resolve()
    try:
        entries = read_record(root)
    except FileNotFoundError:
        entries = {}
    chosen: dict[str, str] = {}
    for given in paths:
        rel = _inside(root, Path(given))
        target = root / rel if rel else root
        if target.is_symlink():
            raise TrustRecordError(f"{given} is a link: only regular files and folders of the task folder are "
                                   "recorded")
        if target.is_dir():
            rels = [r for r in code_files(root) if not rel or r.startswith(rel + "/")]
            if not rels:
                raise TrustRecordError(f"{given} holds no .py file to record")
        elif target.is_file() and rel.endswith(CODE_SUFFIX):
            rels = [rel]
        else:
            raise TrustRecordError(f"{given} is not a .py file or a folder in {root}")
        for r in rels:  # (code_files does not enter linked folders; file_digest does not follow a link)
            digest = file_digest(root / r)
            if digest is None:
                raise TrustRecordError(f"{root / r} is not a regular file of at most {MAX_CODE_BYTES} bytes (a link "
                                       "is not recorded)")
            if _LINE.fullmatch(f"{digest}  {r}") is None:
                raise TrustRecordError(f"{root / r}: {r!r} cannot be recorded (a hidden folder such as .drafts, "
                                       "or a name with characters other than letters, digits, _, . and -)")
            chosen[r] = digest
    dropped = tuple(sorted(r for r in entries if r not in chosen and not os.path.lexists(root / r)))
    new = {r: d for r, d in entries.items() if r not in dropped} | chosen
    with atomic_path(record_path(root)) as tmp:
        tmp.write_text(render_record(new), encoding="ascii")
    forget()
    return TrustUpdate(record=record_path(root),
                       added=tuple(sorted(r for r in chosen if r not in entries)),
                       changed=tuple(sorted(r for r in chosen if r in entries and entries[r] != chosen[r])),
                       unchanged=tuple(sorted(r for r in chosen if entries.get(r) == chosen[r])),
                       dropped=dropped)
