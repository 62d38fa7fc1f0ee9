"""How long does generating one verified task take with the offline backend, after warm-up?

In one process: a warm-up task (first SAPIEN scene and first rendered frame compile shaders: ~10-15 s), then
``--tasks`` more tasks, each timed from proposal to committed folder (renders, refinement rounds, reward-code probe,
the solvability gate's ``--gate-attempts`` solver attempts in a child process, proposals the gate dropped, and
commit included), into a scratch folder. Prints each task's seconds and gate result, the mean, and the ratio to the
issue's target (<= 120 s per verified task on a 2-core machine after warm-up), plus the physical-check violations
before -> after refinement.

Run: ``.venv/bin/python benchmarks/generate.py [--tasks 3] [--seed 0]``.
"""

from __future__ import annotations

# isort: off
import gendex_envs.blas  # noqa: F401  (first: it pins OpenBLAS's kernels before numpy loads)
# isort: on

import argparse
import logging
import platform
import tempfile
import time
from pathlib import Path

from generator.backends.offline import OfflineBackend
from generator.pipeline import generate

TARGET_S = 120.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--tasks", type=int, default=3, help="timed tasks after the warm-up task")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--gate-attempts", type=int, default=10, help="solvability-gate attempts per task (0: no gate)")
    ap.add_argument("--refine-tasks", type=int, default=20,
                    help="tasks generated with ONE scene candidate each, to measure what refinement alone fixes "
                         "(0 skips)")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING)
    print(f"machine: {platform.node()} ({platform.processor() or platform.machine()}), "
          f"python {platform.python_version()}")
    with tempfile.TemporaryDirectory(prefix="gendex-genbench-") as tmp:
        root = Path(tmp)
        t0 = time.perf_counter()
        factory = lambda: OfflineBackend(seed=args.seed)  # noqa: E731
        warm = generate(factory, root, n=1, seed=args.seed, command="benchmark warm-up",
                        gate_attempts=args.gate_attempts)
        print(f"warm-up task {warm[0].committed.env_id}: {time.perf_counter() - t0:.1f} s")
        times: list[float] = []
        times_violations: list[int] = []
        seen = 0

        def progress(summary) -> None:
            nonlocal seen
            seen += 1
            times.append(summary.seconds)
            times_violations.append(summary.violations_before)
            gate = f", gate {summary.gate.summary()}" if summary.gate else ""
            dropped = f", {len(summary.dropped)} proposal(s) dropped" if summary.dropped else ""
            print(f"task {seen}: {summary.committed.env_id:38s} {summary.seconds:6.1f} s, violations "
                  f"{summary.violations_before} -> {summary.violations_after} in {summary.refine_rounds} round(s)"
                  f"{gate}{dropped}")

        generate(factory, root, n=args.tasks, seed=args.seed + 1, command="benchmark", progress=progress,
                 gate_attempts=args.gate_attempts)
        if args.refine_tasks:
            rows = generate(lambda: OfflineBackend(seed=args.seed + 100), root / "refine", n=args.refine_tasks,
                            seed=args.seed, command="benchmark refine", candidates=1, gate_attempts=0)
            before = sum(r.violations_before for r in rows)
            after = sum(r.violations_after for r in rows)
            dirty = sum(r.violations_before > 0 for r in rows)
            print(f"\nrefinement over {len(rows)} tasks (one scene candidate each, no selection): "
                  f"{before} -> {after} physical-check violations; {dirty} scene(s) had any before, "
                  f"{sum(r.violations_after > 0 for r in rows)} after; rounds used: "
                  f"{sorted(r.refine_rounds for r in rows)}")
            print(f"(candidate selection alone, 3 per task, above: chosen scenes had "
                  f"{sum(1 for t in times_violations if t > 0)} with violations before refinement)")
    mean = sum(times) / len(times)
    print(f"\nmean {mean:.1f} s per task after warm-up; target {TARGET_S:.0f} s; ratio mean/target = "
          f"{mean / TARGET_S:.2f} ({'meets' if mean <= TARGET_S else 'misses'} the target)")


if __name__ == "__main__":
    main()
