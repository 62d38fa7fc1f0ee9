"""Atomic file writes: write to a temporary file in the destination's folder, then rename it over the destination,
so a reader (or a run killed midway) never sees a half-written file."""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` (same suffix); on success it replaces ``path``, world-readable
    (``mkstemp`` creates 0600); on error it is removed and ``path`` is left as it was."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_json(path: str | Path, data, **dump_kwargs) -> Path:
    """Write ``data`` as JSON (``json.dump`` keyword arguments pass through) atomically; returns ``path``."""
    with atomic_path(path) as tmp, tmp.open("w") as f:
        json.dump(data, f, **dump_kwargs)
        f.write("\n")
    return Path(path)
