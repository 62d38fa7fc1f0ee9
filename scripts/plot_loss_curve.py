"""Plot the learning curves that ``gendex bc train`` / ``gendex bc train-multitask`` record in ``bc.json`` (the
smoothed training loss against the gradient step), one line per run, on a log scale.

    .venv/bin/python scripts/plot_loss_curve.py out/bc/mt-state out/bc/mt-pixels --out docs/images/mt_loss.png
"""

from __future__ import annotations

import argparse
import json
import logging
from pathlib import Path

log = logging.getLogger("plot_loss_curve")


def load_curve(run: Path) -> tuple[str, list[int], list[float]]:
    """(label, steps, losses) of one run folder's ``bc.json``; a clear error when it has no curve."""
    path = run / "bc.json"
    if not path.is_file():
        raise SystemExit(f"{run} has no bc.json: not a gendex bc training folder")
    record = json.loads(path.read_text())
    curve = record.get("curve") or []
    if not curve:
        raise SystemExit(f"{path} records no learning curve")
    label = f"{run.name} ({record.get('seconds', '?')} s)"
    return label, [int(s) for s, _ in curve], [float(v) for _, v in curve]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path, help="gendex bc training folders (with bc.json)")
    ap.add_argument("--out", type=Path, required=True, help="PNG to write")
    ap.add_argument("--title", default="Training loss (L1 on normalized action chunks, smoothed)")
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 3.6), dpi=120)
    for run in args.runs:
        label, steps, losses = load_curve(run)
        ax.plot(steps, losses, marker=".", label=label)
    ax.set_yscale("log")
    ax.set_xlabel("gradient step")
    ax.set_ylabel("training loss")
    ax.set_title(args.title, fontsize=9)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out)
    log.info("wrote %s (%d runs)", args.out, len(args.runs))


if __name__ == "__main__":
    main()
