"""Atomic file writes: write to a temporary file in the destination's folder, then rename it over the destination,
so a reader (or a run killed midway) never sees a half-written file.

This is the project's one writer of that kind (``tests/unit/test_atomic_writes.py`` fails on a hand-written
temp-file-and-rename elsewhere):

- :func:`atomic_path`: a temporary path for writers that take a path (PIL, ``torch.save``, streamed ``open``);
- :func:`write_text`, :func:`write_bytes`, :func:`write_json`: whole contents at once;
- :func:`atomic_dir`: a folder built beside its destination and renamed into place.

On error the temporary file (or folder) is removed and the destination is left as it was; the error propagates
unchanged (an ``OSError`` stays an ``OSError``, so callers' typed errors still wrap it). ``fsync=True`` flushes the
contents to disk before the rename, for records that must survive a power cut, not only a killed process.
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


def _fsync_file(path: str | Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextmanager
def atomic_path(path: str | Path, *, fsync: bool = False) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` (same suffix, so writers that pick a format by suffix still do); on
    success it replaces ``path``, world-readable (``mkstemp`` creates 0600); on error it is removed and ``path`` is
    left as it was. ``fsync``: flush the temporary file to disk before the rename."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o644)
        if fsync:
            _fsync_file(tmp)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_bytes(path: str | Path, data: bytes, *, fsync: bool = False) -> Path:
    """Write ``data`` atomically; returns ``path``."""
    with atomic_path(path, fsync=fsync) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text(path: str | Path, text: str, *, encoding: str = "utf-8", fsync: bool = False) -> Path:
    """Write ``text`` atomically (no newline translation: the bytes are ``text.encode(encoding)``); returns
    ``path``."""
    return write_bytes(path, text.encode(encoding), fsync=fsync)


def write_json(path: str | Path, data, *, fsync: bool = False, **dump_kwargs) -> Path:
    """Write ``data`` as JSON (``json.dump`` keyword arguments pass through) and a final newline, atomically;
    returns ``path``."""
    with atomic_path(path, fsync=fsync) as tmp, tmp.open("w") as f:
        json.dump(data, f, **dump_kwargs)
        f.write("\n")
    return Path(path)


@contextmanager
def atomic_dir(path: str | Path, *, replace: bool = False) -> Iterator[Path]:
    """Yield a new empty folder beside ``path`` (hidden, same parent, ``mkdtemp``'s mode 0700 unless the writer
    changes it); on success it is renamed to ``path``.

    ``path`` must not exist then, unless ``replace``: the old folder is removed first (not atomic as a pair: a crash
    between the two leaves no folder, never a half-copied one). If ``path`` appeared meanwhile and ``replace`` is
    false, the new folder is removed and :class:`FileExistsError` raised (a process that lost a race to build the
    same thing can catch it and use the winner's). On error the new folder is removed and ``path`` left as it was."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".building", dir=path.parent))
    try:
        yield tmp
        if replace and (path.exists() or path.is_symlink()):
            if path.is_dir() and not path.is_symlink():
                shutil.rmtree(path)
            else:
                path.unlink()
        try:
            os.rename(tmp, path)
        except OSError as exc:
            if exc.errno in (errno.EEXIST, errno.ENOTEMPTY):
                raise FileExistsError(errno.EEXIST, "exists already", str(path)) from exc
            raise
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
