"""Stage 7, commit: move a finished task from its staging folder into ``<root>/<Name>/v<N>/`` atomically.

A task is assembled in ``<root>/.staging/<id>/`` (hidden, never discovered by the registry). When complete, one
``rename`` publishes it: the whole ``<Name>`` folder when the name is new, else the next free ``v<N>`` inside it.
A run killed before the rename leaves only the hidden staging folder, which the next run removes.
"""

from __future__ import annotations

import logging
import os
import re
import shutil
import uuid
from dataclasses import dataclass
from pathlib import Path

from generator.errors import CommitError

log = logging.getLogger(__name__)

STAGING = ".staging"
REQUIRED_FILES = ("task.yaml", "reward.py", "proposal.json", "generation.json", "transcript.jsonl")
_VERSION = re.compile(r"^v(\d+)$")


@dataclass(frozen=True)
class CommittedTask:
    name: str
    version: int
    path: Path

    @property
    def env_id(self) -> str:
        return f"GenDex/{self.name}-v{self.version}"


def clean_staging(root: Path) -> int:
    """Remove staging folders left by killed runs; returns how many."""
    staging = root / STAGING
    if not staging.is_dir():
        return 0
    stale = list(staging.iterdir())
    for p in stale:
        shutil.rmtree(p, ignore_errors=True)
    if stale:
        log.info("removed %d unfinished task folder(s) from %s", len(stale), staging)
    return len(stale)


def new_staging(root: Path) -> Path:
    d = root / STAGING / uuid.uuid4().hex[:12]
    d.mkdir(parents=True)
    return d


def next_version(root: Path, name: str) -> int:
    d = root / name
    if not d.is_dir():
        return 0
    versions = [int(m.group(1)) for p in d.iterdir() if (m := _VERSION.match(p.name))]
    return max(versions) + 1 if versions else 0


def commit_task(root: Path, name: str, staged: Path) -> CommittedTask:
    """Publish ``staged`` (a complete task folder) as ``root/name/v<N>``; raises :class:`CommitError`."""
    missing = [f for f in REQUIRED_FILES if not (staged / f).is_file()]
    if missing:
        raise CommitError(f"task {name!r} is incomplete, not committing it: missing {missing}")
    for _ in range(100):
        version = next_version(root, name)
        wrapper = staged.parent / f"{staged.name}-publish"
        target_parent = root / name
        try:
            if not target_parent.exists():
                (wrapper / f"v{version}").parent.mkdir(parents=True, exist_ok=True)
                os.rename(staged, wrapper / f"v{version}")
                try:
                    os.rename(wrapper, target_parent)  # the whole <Name> folder appears at once
                except OSError:
                    os.rename(wrapper / f"v{version}", staged)  # someone else created <Name>: retry inside it
                    shutil.rmtree(wrapper, ignore_errors=True)
                    continue
            else:
                os.rename(staged, target_parent / f"v{version}")
        except FileExistsError:
            continue
        except OSError as exc:
            if (target_parent / f"v{version}").exists():
                continue
            raise CommitError(f"could not publish task {name!r} into {root}: {exc}") from exc
        log.info("committed %s", target_parent / f"v{version}")
        return CommittedTask(name, version, target_parent / f"v{version}")
    raise CommitError(f"could not find a free version folder for {name!r} in {root}")
