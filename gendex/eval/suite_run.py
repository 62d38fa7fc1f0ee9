"""``gendex eval``: a policy on every task of a suite, resumable, in parallel, written as LeRobot's ``eval_info.json``.

Every finished episode is appended to ``<out>/episodes.jsonl`` (one JSON object per line); a run that was stopped
goes on with the (task, seed) pairs it lacks. With ``workers > 1`` the tasks are shared among that many processes
(each with its env and its own policy, built from the policy's spec string). At the end ``<out>/eval_info.json``
holds:

- ``per_episode``: LeRobot's fields (``episode_ix``, ``sum_reward``, ``max_reward``, ``success``: the suite's
  metric, ``seed``) plus the task, ``success_once``, ``success_at_end``, length and any failure reason;
- ``per_task``: episodes, successes, ``pc_success`` with its 95 % Wilson interval, ``success_once``, mean episode
  length, env steps, failures;
- ``aggregated``: LeRobot's ``avg_sum_reward``, ``avg_max_reward``, ``pc_success`` (over all episodes, with its
  interval), ``eval_s``, ``eval_ep_s``; and the mean of the per-task rates;
- the suite's name, hash and metric, the policy spec, the GenDex version, and the video files if any were written;
- ``task_digests``: the digest of each task's files as they ran (:meth:`~gendex_envs.task_version.TaskVersion.
  file_digest`). A run whose tasks' files differ from the suite's (the committed versions) is refused unless
  ``allow_changed_tasks``; the leaderboard refuses such a result.
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Callable
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import numpy as np

from gendex.eval.metrics import wilson
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
              allow_changed_tasks: bool = False) -> dict:
    """Evaluate the policy ``spec`` (made by ``resolver(spec)()``) on ``suite``; returns and writes eval_info.
    The tasks registered under the suite's ids must have the suite's files (the committed versions, by digest):
    :class:`~gendex.eval.suite.TaskDigestError` otherwise, unless ``allow_changed_tasks`` (the digests that ran are
    recorded either way).
    ``videos``: the first k episodes of each task are also recorded (``<out>/videos/``). ``backend``
    (:class:`gendex.fanout.Backend`; default ``workers`` local processes) shares the tasks among workers; a
    task's episodes are kept when its job returns, so a worker killed on Ray has the task re-run, not doubled."""
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
    info = eval_info(suite, spec, rows, seeds, time.perf_counter() - t0, task_digests=digests)
    (out / EVAL_INFO).write_text(json.dumps(info, indent=1) + "\n")
    return info


def eval_info(suite: Suite, spec: str, rows: list[dict], seeds: list[int], seconds: float,
              task_digests: dict[str, str] | None = None) -> dict:
    """The eval_info.json of ``rows`` (episode dicts), in the suite's task order and seed order; ``task_digests``:
    the digest of each task's files as they ran (:func:`~gendex.eval.suite.ran_task_digests`)."""
    order = {t: i for i, t in enumerate(suite.tasks)}
    rows = sorted((r for r in rows if r["task"] in order and r["seed"] in set(seeds)),
                  key=lambda r: (order[r["task"]], r["seed"]))
    metric = suite.metric
    per_episode = [{"episode_ix": i, "task": r["task"], "seed": r["seed"], "sum_reward": r["sum_reward"],
                    "max_reward": r["max_reward"], "success": bool(r[metric]), "success_once": r["success_once"],
                    "success_at_end": r["success_at_end"], "length": r["length"], "failure": r["failure"]}
                   for i, r in enumerate(rows)]
    per_task = {}
    for task in suite.tasks:
        mine = [r for r in per_episode if r["task"] == task]
        if not mine:
            continue
        k, n = sum(r["success"] for r in mine), len(mine)
        lo, hi = wilson(k, n)
        fails: dict[str, int] = {}
        for r in mine:
            if r["failure"]:
                fails[r["failure"]] = fails.get(r["failure"], 0) + 1
        per_task[task] = {"episodes": n, "successes": k, "pc_success": 100.0 * k / n,
                          "wilson95": [100.0 * lo, 100.0 * hi],
                          "pc_success_once": 100.0 * sum(r["success_once"] for r in mine) / n,
                          "mean_length": float(np.mean([r["length"] for r in mine])),
                          "env_steps": int(sum(r["length"] for r in mine)), "policy_failures": fails}
    n = len(per_episode)
    k = sum(r["success"] for r in per_episode)
    lo, hi = wilson(k, n)
    aggregated = {"avg_sum_reward": float(np.mean([r["sum_reward"] for r in per_episode])) if n else 0.0,
                  "avg_max_reward": float(np.mean([r["max_reward"] for r in per_episode])) if n else 0.0,
                  "pc_success": 100.0 * k / n if n else 0.0, "wilson95": [100.0 * lo, 100.0 * hi],
                  "mean_task_pc_success": float(np.mean([t["pc_success"] for t in per_task.values()]))
                  if per_task else 0.0,
                  "episodes": n, "env_steps": int(sum(r["length"] for r in per_episode)),
                  "eval_s": round(seconds, 1), "eval_ep_s": round(seconds / n, 2) if n else 0.0}
    complete = all(per_task.get(t, {}).get("episodes") == suite.episodes for t in suite.tasks)
    return {"suite": {"name": suite.name, "hash": suite.hash, "metric": metric, "episodes_per_task": len(seeds),
                      "seeds": [seeds[0], seeds[-1]], "complete": complete},
            "policy": spec, "gendex_version": _gendex_version(), "per_episode": per_episode, "per_task": per_task,
            "aggregated": aggregated, "video_paths": [r["video"] for r in rows if r.get("video")],
            **({"task_digests": {t: task_digests[t] for t in suite.tasks if t in task_digests}}
               if task_digests is not None else {})}


__all__ = ["EPISODES_FILE", "EVAL_INFO", "EvalError", "eval_info", "run_suite"]
