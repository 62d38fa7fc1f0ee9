"""Does a larger asset catalog slow down ``import gendex_envs`` or building a task's env? The objects issue's check:
both within 10 % of what they were before the catalog grew (the catalog loads lazily).

Runs, in fresh processes and alternating between two checkouts of the project (``--base``: a worktree of the commit
before the catalog grew; ``--head``: this one, default), ``--repeats`` times each:

- ``import gendex_envs, gymnasium``;
- ``gym.make(task)`` and the first ``reset`` for each of ``--tasks`` (tasks both checkouts have), render backend off,
  one process per task.

Prints the median seconds of each, and head / base; ``--json PATH`` writes the record. Both checkouts run with this
checkout's virtual environment (the same packages), so what differs is the project's code and data.

Run: ``.venv/bin/python benchmarks/catalog_cost.py --base /tmp/before [--repeats 7]``, where ``/tmp/before`` is
``git worktree add /tmp/before <commit>``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
IMPORT = ("import time; t = time.perf_counter(); import gendex_envs, gymnasium; "
          "print(time.perf_counter() - t)")
MAKE = ("import gendex_envs, gymnasium as gym, time; t = time.perf_counter(); "
        "env = gym.make({task!r}, obs_mode='state', render_backend='none'); env.reset(seed=0); "
        "print(time.perf_counter() - t); env.close()")
TASKS = ("GenDex/PutAppleBowl-v1", "GenDex/OpenCabinet-v2", "GenDex/CloseMicrowave-v2")


def timed(checkout: Path, code: str) -> float:
    env = dict(os.environ, PYTHONPATH=str(checkout))
    out = subprocess.run([sys.executable, "-c", code], cwd=checkout, env=env, capture_output=True, text=True,
                         check=True)
    return float(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--base", type=Path, required=True, help="checkout before the catalog grew")
    ap.add_argument("--head", type=Path, default=ROOT, help="checkout to compare (default: this one)")
    ap.add_argument("--tasks", nargs="*", default=list(TASKS), help="tasks to build (none: the import alone)")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    checks = {"import": IMPORT, **{t: MAKE.format(task=t) for t in args.tasks}}
    times: dict[str, dict[str, list[float]]] = {k: {"base": [], "head": []} for k in checks}
    for _ in range(args.repeats):
        for what, code in checks.items():
            for side in ("base", "head"):  # alternating, so load on the machine falls on both alike
                times[what][side].append(timed(getattr(args, side), code))
    rows = {k: {s: statistics.median(v) for s, v in t.items()} for k, t in times.items()}
    print(f"machine: {platform.machine()}, {os.cpu_count()} CPUs; {args.repeats} repeats, medians (s)")
    for k, r in rows.items():
        print(f"{k:32s} base {r['base']:.3f}  head {r['head']:.3f}  head/base {r['head'] / r['base']:.3f}")
    if args.json:
        args.json.write_text(json.dumps({"repeats": args.repeats, "medians_s": rows, "samples_s": times},
                                        indent=1) + "\n")


if __name__ == "__main__":
    main()
