"""How well and how cheaply does the stage executor collect successful episodes?

Per task, in one run:

(a) success rate of ``--episodes`` seeded attempts (seeds ``--seed`` ..), through ``gendex.data.collector``
    exactly as ``gendex collect`` runs them (one CPU env, ``pd_joint_pos``, successful episodes kept, nothing written
    but the dataset in a scratch folder);
(b) env steps per successful trajectory (all attempts' steps / successes) and what 1000 successes would cost;
(c) successes per wall-clock minute with 1 and with 2 worker processes (``--workers-trial`` successes each), and
    their ratio. On a 2-core machine the ideal ratio is 2.

The issue's targets: (a) >= 95 %, (b) <= 1 M env steps per 1000 successes.

Without ``--tasks`` it measures the newest registered version of each reference task (``REFERENCE_TASKS``), so the
default follows the tasks as they gain versions.

Run: ``.venv/bin/python benchmarks/collect.py [--tasks GenDex/PutAppleBowl-v1 ...] [--episodes 50] [--seed S]``.
"""

from __future__ import annotations

import argparse
import logging
import os
import platform
import tempfile
import time
from pathlib import Path

import gendex_envs  # noqa: F401  (registers the GenDex/* ids)
from gendex.data.collector import CollectConfig, collect
from gendex.solve import SOLVER_ENV_KWARGS, SOLVERS
from gendex_envs.registry import REFERENCE_TASKS, resolve_task


def newest_reference_ids() -> list[str]:
    """The env id of the highest registered version of each reference task."""
    return [resolve_task(name).env_id for name in REFERENCE_TASKS]


def run(task: str, n: int, seed: int, workers: int, formats: tuple[str, ...] = ("h5",)):
    with tempfile.TemporaryDirectory(prefix="gendex-bench-") as tmp:
        cfg = CollectConfig(task_id=task, num_success=n, out=Path(tmp) / "ds", formats=formats, seed=seed,
                            max_attempts=n, **SOLVER_ENV_KWARGS["stages"])
        t0 = time.perf_counter()
        state = collect(cfg, SOLVERS["stages"], workers=workers)
        return state, time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="+", help="env ids (default: the newest version of each reference task)")
    ap.add_argument("--episodes", type=int, default=50)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers-trial", type=int, default=60, help="attempts per worker-count timing (0: skip)")
    args = ap.parse_args()
    logging.basicConfig(level=logging.ERROR)
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs")
    rows = []
    for task in args.tasks or newest_reference_ids():
        state, secs = run(task, args.episodes, args.seed, workers=1)
        rate = state.successes / state.attempts if state.attempts else 0.0
        per = state.env_steps_per_success
        print(f"{task}: {state.successes}/{state.attempts} succeeded ({100 * rate:.0f} %), "
              f"{state.env_steps} env steps, {per:.1f} env steps per success "
              f"-> {per * 1000 / 1e6:.3f} M env steps per 1000 successes, {secs:.1f} s", flush=True)
        timing = {}
        if args.workers_trial and state.successes:
            for w in (1, 2):
                s, t = run(task, args.workers_trial, args.seed + 10_000, workers=w)
                timing[w] = 60.0 * s.successes / t
                print(f"  {w} worker(s): {s.successes}/{s.attempts} in {t:.1f} s = {timing[w]:.1f} successes/min",
                      flush=True)
            print(f"  ratio 2 workers / 1 worker  {timing[2] / timing[1]:.2f}" if timing[1] else "", flush=True)
        rows.append((task, rate, per, timing))
    print("\nsummary (task, success rate, env steps/success, successes/min 1w, 2w)")
    for task, rate, per, timing in rows:
        print(f"  {task:28s} {100 * rate:5.1f} %  {per:9.1f}  {timing.get(1, float('nan')):7.1f}  "
              f"{timing.get(2, float('nan')):7.1f}")


if __name__ == "__main__":
    main()
