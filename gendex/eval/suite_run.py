"""``gendex eval``: a policy on every task of a suite, resumable, in parallel, written as LeRobot's ``eval_info.json``.

Every finished episode is appended to ``<out>/episodes.jsonl`` (one JSON object per line); a run that was stopped
goes on with the (task, seed) pairs it lacks. With ``workers > 1`` the tasks are shared among that many processes
(each with its env and its own policy, built from the policy's spec string). At the end ``<out>/eval_info.json``
holds the result in lerobot 0.4's layout (``per_task``, ``per_group``, ``overall``) with GenDex's extras: Wilson
intervals, every episode's seed, length and failure, the suite's name, hash and seeds, the policy spec, the GenDex
version (:mod:`gendex.eval.eval_info`), and ``task_digests``: the digest of each task's files as they ran
(:meth:`~gendex_envs.task_version.TaskVersion.file_digest`). A run whose tasks' files differ from the suite's (the
committed versions) is refused unless ``allow_changed_tasks``; the leaderboard refuses such a result.
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Callable
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from gendex.eval.eval_info import build as build_info
from gendex.eval.runner import EpisodeResult, evaluate_task
from gendex.eval.suite import Suite, check_task_digests, ran_task_digests
from gendex.fanout import Backend, ordered_map
from gendex_envs.errors import GenDexError

log = logging.getLogger(__name__)

EPISODES_FILE = "episodes.jsonl"
EVAL_INFO = "eval_info.json"
RUN_FILE = "eval_run.json"
"""What the result folder evaluates (suite, its hash, policy): a resumed run must be the same evaluation."""
Resolver = Callable[[str], Callable[[], object]]


class EvalError(GenDexError, ValueError):
    """An evaluation cannot run as asked (seeds a policy was trained on, a result folder of another run)."""


def _gendex_version() -> str:
    try:
        return version("gendex")
    except PackageNotFoundError:
        return "0+unknown"


def _done(out: Path, suite: Suite, spec: str, digests: dict[str, str]) -> list[dict]:
    path = out / EPISODES_FILE
    rows = [json.loads(line) for line in path.read_text().splitlines() if line.strip()] if path.is_file() else []
    head = out / RUN_FILE
    if head.is_file():
        prev = json.loads(head.read_text())
        if (prev["suite"], prev["suite_hash"], prev["policy"]) != (suite.name, suite.hash, spec):
            raise EvalError(f"{out} holds an evaluation of {prev['policy']} on {prev['suite']} "
                            f"({prev['suite_hash'][:12]}); use another --out for {spec} on {suite.name}")
        changed = sorted(t for t, d in prev.get("task_digests", {}).items() if t in digests and digests[t] != d)
        if changed:
            raise EvalError(f"{out} holds episodes run on other files of {changed} (task digests differ); use "
                            "another --out")
    return rows


def _task_worker():
    """A worker of :func:`gendex.fanout.ordered_map`: evaluates one task's seeds per job."""
    return _task_job


def _task_job(job: tuple) -> list[dict]:
    task, seeds, spec, resolver, env_kwargs, max_steps, videos, video_dir = job
    import torch

    torch.set_num_threads(1)
    results = evaluate_task(task, resolver(spec), seeds, env_kwargs=env_kwargs, max_episode_steps=max_steps,
                            videos=videos, video_dir=video_dir)
    return [r.to_dict() for r in results]


def run_suite(suite: Suite, spec: str, resolver: Resolver, out: Path, *, episodes: int | None = None,
              workers: int = 1, training_seeds: list[int] | None = None, videos: int = 0,
              progress: Callable[[EpisodeResult | dict], None] | None = None, backend: Backend | None = None,
              allow_changed_tasks: bool = False, groups: dict[str, str] | None = None) -> dict:
    """Evaluate the policy ``spec`` (made by ``resolver(spec)()``) on ``suite``; returns and writes eval_info.
    The tasks registered under the suite's ids must have the suite's files (the committed versions, by digest):
    :class:`~gendex.eval.suite.TaskDigestError` otherwise, unless ``allow_changed_tasks`` (the digests that ran are
    recorded either way).
    ``videos``: the first k episodes of each task are also recorded (``<out>/videos/``). ``backend``
    (:class:`gendex.fanout.Backend`; default ``workers`` local processes) shares the tasks among workers; a
    task's episodes are kept when its job returns, so a worker killed on Ray has the task re-run, not doubled.
    ``groups``: each task's group in the result (its skills; default the suite's name)."""
    backend = backend or Backend.from_options(workers)
    seeds = suite.seeds(episodes)
    leaked = sorted(set(seeds) & set(training_seeds or ()))
    if leaked:
        raise EvalError(f"the policy was trained on seeds {leaked[:5]}{'...' if len(leaked) > 5 else ''} of suite "
                        f"{suite.name}'s; evaluating it there would measure memory, not skill")
    digests = ran_task_digests(suite.tasks)
    if allow_changed_tasks:
        log.warning("not checking the task files against suite %s's (allow_changed_tasks): the leaderboard will "
                    "refuse this result if they differ", suite.name)
    else:
        check_task_digests(suite, digests, f"suite {suite.name}: ")
    out.mkdir(parents=True, exist_ok=True)
    rows = _done(out, suite, spec, digests)
    (out / RUN_FILE).write_text(json.dumps({"suite": suite.name, "suite_hash": suite.hash, "policy": spec,
                                            "task_digests": digests}) + "\n")
    have = {(r["task"], r["seed"]) for r in rows}
    jobs = [(t, [s for s in seeds if (t, s) not in have], spec, resolver, suite.env_kwargs, suite.max_episode_steps,
             max(0, videos - sum(1 for r in rows if r["task"] == t)), out / "videos") for t in suite.tasks]
    jobs = [j for j in jobs if j[1]]
    t0 = time.perf_counter()
    with (out / EPISODES_FILE).open("a") as log_file:
        def keep(row: dict) -> None:
            rows.append(row)
            log_file.write(json.dumps(row) + "\n")
            log_file.flush()
            if progress is not None:
                progress(row)

        if backend.kind == "local":
            for task, todo, _, _, env_kwargs, max_steps, k, video_dir in jobs:
                evaluate_task(task, resolver(spec), todo, env_kwargs=env_kwargs, max_episode_steps=max_steps,
                              progress=lambda r: keep(r.to_dict()), videos=k, video_dir=video_dir)
        else:
            for done in ordered_map(_task_worker, jobs, backend, ahead=len(jobs)):
                for row in done:
                    keep(row)
    info = eval_info(suite, spec, rows, seeds, time.perf_counter() - t0, task_digests=digests, groups=groups)
    (out / EVAL_INFO).write_text(json.dumps(info, indent=1) + "\n")
    return info


def eval_info(suite: Suite, spec: str, rows: list[dict], seeds: list[int], seconds: float,
              task_digests: dict[str, str] | None = None, groups: dict[str, str] | None = None) -> dict:
    """The eval_info.json of ``rows`` (episode dicts), in the suite's task order and seed order, in lerobot 0.4's
    layout (:func:`gendex.eval.eval_info.build`); ``task_digests``: the digest of each task's files as they ran
    (:func:`~gendex.eval.suite.ran_task_digests`); ``groups``: each task's group (its skills)."""
    return build_info(suite, spec, rows, seeds, seconds, gendex_version=_gendex_version(), task_digests=task_digests,
                      groups=groups)


__all__ = ["EPISODES_FILE", "EVAL_INFO", "EvalError", "eval_info", "run_suite"]
