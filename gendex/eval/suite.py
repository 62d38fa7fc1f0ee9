"""Benchmark suites as data: ``suites/<name>.yaml``.

A suite fixes what a result on it means: versioned task ids, the evaluation seeds (the same for every task,
``seed .. seed + episodes - 1``, disjoint from every dataset's and from the solvability gate's), episodes per task
(default 50, as LIBERO and RoboCasa), the metric that ranks (``success_at_end``, ManiSkill's default;
``success_once`` is reported too), ``gym.make`` keyword arguments and an optional step limit. A result carries the
suite file's SHA-256, so two results are comparable exactly when their hashes agree.

A suite names task *versions*, and a task version is fixed by its files: the suite's tasks are the versions as
committed in ``generated_tasks/`` (a published version never changes), whose digests
(:meth:`~gendex_envs.task_version.TaskVersion.file_digest`) :func:`suite_task_digests` gives. ``gendex eval`` records
the digest of each task it ran and refuses to run a task whose files differ from the committed ones (a folder on
``GENDEX_TASKS_PATH`` registered over the id with ``GENDEX_ALLOW_OVERRIDE=1``) unless asked; the leaderboard refuses
a result whose digests differ. The digests are not written into the suite files: they follow from the versioned ids,
and writing them would change every suite's hash, marking every filed result stale with no task changed.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path

import dacite

from gendex_envs.errors import GenDexError
from gendex_envs.library import library_dir
from gendex_envs.typed_yaml import load_yaml_bounded

SUITES_DIR = library_dir("suites")  # the checkout's suites/, or the installed wheel's (gendex_envs.library)
METRICS = ("success_at_end", "success_once")
SEED_FLOOR = 1_000_000
"""Suite seeds start at or above this: datasets use 0 .. their manifests' max attempts, benchmarks 1 000-97 000."""


class SuiteError(GenDexError, ValueError):
    """A suite file is malformed or unknown."""


class TaskDigestError(SuiteError):
    """The files of a suite's task differ from the suite's (the task version as committed)."""


def suite_task_digests(suite: Suite) -> dict[str, str]:
    """Task id -> digest of the suite's task version as committed (``generated_tasks/<Name>/v<N>``), whatever is
    registered under the id in this process; :class:`SuiteError` for a task the repository does not hold."""
    from gendex_envs.registry import committed_version

    out = {}
    for task in suite.tasks:
        version = committed_version(task)
        if version is None:
            raise SuiteError(f"suite {suite.name}: {task} is not a committed task version (generated_tasks/"
                             "<Name>/v<N>); a suite's tasks must be, so that their files are fixed")
        out[task] = version.file_digest()
    return out


def ran_task_digests(tasks: list[str] | tuple[str, ...]) -> dict[str, str]:
    """Task id -> digest of the folder registered under the id in this process: what ``gym.make(id)`` runs."""
    from gendex_envs.registry import resolve_task

    return {task: resolve_task(task).file_digest() for task in tasks}


def check_task_digests(suite: Suite, ran: dict[str, str], where: str = "") -> None:
    """:class:`TaskDigestError` naming every task of ``ran`` whose digest differs from the suite's."""
    want = suite_task_digests(suite)
    bad = [f"{task}: ran on files with digest {ran[task]}, the suite's (committed) version has {want[task]}"
           for task in ran if task in want and ran[task] != want[task]]
    if bad:
        raise TaskDigestError(f"{where}{'; '.join(bad)}. The task files are not the suite's: a folder on "
                              "GENDEX_TASKS_PATH replaced the committed version, or the committed files were changed")


@dataclass(frozen=True)
class Suite:
    name: str
    description: str
    tasks: tuple[str, ...]
    seed: int
    """First evaluation seed; every task is evaluated on ``seed .. seed + episodes - 1``."""
    episodes: int = 50
    metric: str = "success_at_end"
    env_kwargs: dict = field(default_factory=dict)
    max_episode_steps: int | None = None
    """Step limit of every episode (None: each task's own)."""
    hash: str = ""
    """SHA-256 of the suite file (set when loaded)."""

    def seeds(self, episodes: int | None = None) -> list[int]:
        return list(range(self.seed, self.seed + (episodes or self.episodes)))


def suite_path(name: str | Path) -> Path:
    p = Path(name)
    return p if p.suffix in (".yaml", ".yml") and p.is_file() else SUITES_DIR / f"{name}.yaml"


def load_suite(name: str | Path) -> Suite:
    """The suite ``suites/<name>.yaml`` (or a suite file), checked, with its hash."""
    path = suite_path(name)
    if not path.is_file():
        known = sorted(p.stem for p in SUITES_DIR.glob("*.yaml"))
        raise SuiteError(f"no suite {str(name)!r}; known: {', '.join(known) or 'none'} (in {SUITES_DIR})")
    data = path.read_bytes()
    raw = load_yaml_bounded(data, str(path), SuiteError)  # a suite file may come from anyone
    try:
        suite = dacite.from_dict(Suite, {**raw, "hash": hashlib.sha256(data).hexdigest()},
                                 config=dacite.Config(strict=True, cast=[tuple]))
    except (dacite.DaciteError, TypeError) as exc:
        raise SuiteError(f"{path}: {exc}") from exc
    problems = []
    if suite.name != path.stem:
        problems.append(f"name {suite.name!r} must equal the file's name {path.stem!r}")
    if suite.metric not in METRICS:
        problems.append(f"metric {suite.metric!r} is not one of {list(METRICS)}")
    if suite.seed < SEED_FLOOR:
        problems.append(f"seed {suite.seed} is below {SEED_FLOOR}, where dataset seeds live")
    if suite.episodes < 1 or not suite.tasks or len(set(suite.tasks)) != len(suite.tasks):
        problems.append("episodes must be >= 1 and tasks a non-empty list without repeats")
    bad = [t for t in suite.tasks if not t.startswith("GenDex/") or "-v" not in t]
    if bad:
        problems.append(f"tasks must be versioned GenDex ids (GenDex/<Name>-v<N>): {bad}")
    if problems:
        raise SuiteError(f"{path}: " + "; ".join(problems))
    return suite


__all__ = ["METRICS", "SEED_FLOOR", "SUITES_DIR", "Suite", "SuiteError", "TaskDigestError", "check_task_digests",
           "load_suite", "ran_task_digests", "suite_path", "suite_task_digests"]
