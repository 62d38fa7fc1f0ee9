"""Successes per minute of `gendex collect` with 1 and 2 workers, on local processes or Ray, in one run.

For each worker count the same attempts (seeds ``--seed`` ..) are collected into a scratch folder with the stage
solver, exactly as ``gendex collect --workers K [--ray]`` runs them, and two rates are printed:

* **end to end**: successes / wall time of the whole call (starting the workers and Ray included);
* **steady**: successes after the first / time from the first committed success to the last (what a long
  collection converges to: the start-up is paid once).

The ratio 2 workers / 1 worker is the scaling; on a 2-core machine the ideal is 2 and the project's goal 1.8
(steady). The kept seeds of both runs are compared: fanning out must not change what is collected.

Run: ``.venv/bin/python benchmarks/scaling.py [--backend ray|process] [--successes 16] [--seed 5000]``.
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
from gendex.fanout import Backend
from gendex.solve import SOLVER_ENV_KWARGS, SOLVERS


def run(task: str, n: int, seed: int, backend: Backend) -> dict:
    stamps: list[float] = []
    last = [0]

    def progress(state) -> None:
        if state.successes > last[0]:
            last[0] = state.successes
            stamps.append(time.perf_counter())

    with tempfile.TemporaryDirectory(prefix="gendex-scaling-") as tmp:
        cfg = CollectConfig(task_id=task, num_success=n, out=Path(tmp) / "ds", formats=("lerobot",), seed=seed,
                            **SOLVER_ENV_KWARGS["stages"])
        t0 = time.perf_counter()
        state = collect(cfg, SOLVERS["stages"], progress, backend=backend)
        wall = time.perf_counter() - t0
    steady = (len(stamps) - 1) / (stamps[-1] - stamps[0]) * 60 if len(stamps) > 2 else float("nan")
    return {"successes": state.successes, "attempts": state.attempts, "wall_s": wall,
            "end_to_end": state.successes / wall * 60, "steady": steady, "seeds": state.kept_seeds}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", default="GenDex/PutAppleBowl-v1")
    ap.add_argument("--successes", type=int, default=16)
    ap.add_argument("--seed", type=int, default=5000)
    ap.add_argument("--backend", choices=("ray", "process"), default="ray")
    args = ap.parse_args()
    logging.basicConfig(level=logging.ERROR)
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs; {args.task}, "
          f"{args.successes} successes from seed {args.seed}, backend {args.backend}", flush=True)
    rows = {}
    for workers in (1, 2):
        r = rows[workers] = run(args.task, args.successes, args.seed, Backend(args.backend, workers))
        print(f"{workers} worker{'s' if workers > 1 else ' '}: {r['successes']}/{r['attempts']} in {r['wall_s']:.1f} s "
              f"-> {r['end_to_end']:.2f} successes/min end to end, {r['steady']:.2f} steady", flush=True)
    same = rows[1]["seeds"] == rows[2]["seeds"]
    print(f"scaling 2/1 workers: end to end {rows[2]['end_to_end'] / rows[1]['end_to_end']:.2f}x, "
          f"steady {rows[2]['steady'] / rows[1]['steady']:.2f}x (goal >= 1.8); same seeds kept: {same}")


if __name__ == "__main__":
    main()
