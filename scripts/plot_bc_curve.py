"""Plot behaviour-cloning success against the number of demonstrations, from ``gendex bc train --eval-episodes``
runs (each run folder holds ``eval.json``), one line per task with 95 % Wilson intervals.

    .venv/bin/python scripts/plot_bc_curve.py out/bc/apple-* out/bc/bottle-* --out docs/images/bc_curve.png
"""

from __future__ import annotations

import argparse
import json
import logging
from collections import defaultdict
from pathlib import Path

log = logging.getLogger("plot_bc_curve")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path, help="gendex bc train output folders (with eval.json)")
    ap.add_argument("--out", type=Path, required=True, help="PNG to write")
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    by_task: dict[str, list[tuple[int, float, float, float]]] = defaultdict(list)
    for run in args.runs:
        path = run / "eval.json"
        if not path.is_file():
            raise SystemExit(f"{run} has no eval.json: train it with --eval-episodes N")
        r = json.loads(path.read_text())
        lo, hi = r["wilson95"]
        by_task[r["task"]].append((r["demos"], 100 * r["rate"], 100 * lo, 100 * hi))
    fig, ax = plt.subplots(figsize=(5.5, 3.6), dpi=120)
    for task, rows in sorted(by_task.items()):
        rows.sort()
        x = [d for d, *_ in rows]
        y = [s for _, s, _, _ in rows]
        err = [[s - lo for _, s, lo, _ in rows], [hi - s for _, s, _, hi in rows]]
        ax.errorbar(x, y, yerr=err, marker="o", capsize=3, label=task.split("/")[-1])
    ax.set_xscale("log", base=2)
    ax.set_xticks(sorted({d for rows in by_task.values() for d, *_ in rows}))
    ax.get_xaxis().set_major_formatter(matplotlib.ticker.ScalarFormatter())
    ax.set_ylim(0, 105)
    ax.set_xlabel("demonstrations")
    ax.set_ylabel("success at the end (%), 50 unseen seeds")
    ax.set_title("Behaviour cloning on GenDex datasets")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out)
    log.info("wrote %s (%d tasks, %d runs)", args.out, len(by_task), len(args.runs))


if __name__ == "__main__":
    main()
