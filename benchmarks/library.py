"""Does every committed task still solve on seeds nobody looked at?

The solvability gate measured each task when it was committed, on the task's own gate seeds. This re-measures the
latest version of every registered task (or ``--tasks``) with the stage executor on ``--attempts`` new seeds
(``--seed`` .., the same for every task, disjoint from the gate's 50 000 000+ range), ``--workers`` tasks at a time
in separate processes, and prints per task the stored gate rate beside the new one, then how many tasks are below
``--min-rate`` (the task-library issue asks >= 0.8 stored and >= 0.7 re-measured).

Run: ``.venv/bin/python benchmarks/library.py [--attempts 10] [--seed 97000] [--workers 2] [--json OUT]``.
"""

from __future__ import annotations

# isort: off
import gendex_envs.blas  # noqa: F401  (first: it pins OpenBLAS's kernels before numpy loads)
# isort: on

import argparse
import json
import logging
import multiprocessing as mp
import time
from pathlib import Path


def _one(job: tuple[str, str, list[int]]) -> dict:
    env_id, folder, seeds = job
    from generator.steps.gate import measure

    t0 = time.perf_counter()
    r = measure(Path(folder), seeds=seeds)
    return {"env_id": env_id, "successes": r.successes, "attempts": r.attempts, "rate": r.rate,
            "env_steps_per_success": r.env_steps_per_success, "failures": r.failures, "seeds": r.seeds,
            "seconds": round(time.perf_counter() - t0, 1)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="*", help="env ids (default: the latest version of every registered task)")
    ap.add_argument("--attempts", type=int, default=10)
    ap.add_argument("--seed", type=int, default=97_000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--min-rate", type=float, default=0.7)
    ap.add_argument("--json", type=Path, help="write every task's result here")
    args = ap.parse_args()
    logging.basicConfig(level=logging.ERROR)
    from gendex_envs.registry import registered_tasks
    from generator.stats import latest_versions

    versions = registered_tasks()
    chosen = {k: versions[k] for k in args.tasks} if args.tasks else latest_versions(versions)
    seeds = list(range(args.seed, args.seed + args.attempts))
    jobs = [(k, str(v.root), seeds) for k, v in sorted(chosen.items())]
    stored = {k: v.provenance().get("solvability") for k, v in chosen.items()}
    t0 = time.perf_counter()
    rows = []
    with mp.get_context("spawn").Pool(args.workers) as pool:
        for row in pool.imap_unordered(_one, jobs):
            gate = stored[row["env_id"]]
            row["gate_rate"] = gate["successes"] / gate["planned_attempts"] if gate else None
            rows.append(row)
            g = "  —  " if row["gate_rate"] is None else f"{row['gate_rate']:.2f}"
            print(f"{row['env_id']:60s} gate {g}  new {row['successes']:2d}/{row['attempts']}"
                  f"  {row['seconds']:6.1f} s  {', '.join(f'{k} x{v}' for k, v in row['failures'].items())}",
                  flush=True)
    low = sorted((r for r in rows if r["rate"] < args.min_rate), key=lambda r: r["rate"])
    rates = [r["rate"] for r in rows]
    print(f"\n{len(rows)} tasks, seeds {seeds[0]}..{seeds[-1]}, {time.perf_counter() - t0:.0f} s: mean rate "
          f"{sum(rates) / len(rates):.2f}, lowest {min(rates):.2f}; {len(low)} below {args.min_rate}"
          + (": " + ", ".join(f"{r['env_id']} {r['rate']:.1f}" for r in low) if low else ""))
    if args.json:
        args.json.write_text(json.dumps(sorted(rows, key=lambda r: r["env_id"]), indent=1) + "\n")


if __name__ == "__main__":
    main()
