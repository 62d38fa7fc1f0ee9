"""Does doing nothing, or flailing, solve a suite's tasks? Checks baseline runs of a suite against the 5 % bound.

A benchmark task that holding still or random actions solve measures nothing. The benchmark issue bounds both at
5 % over a suite's 50 episodes per task, counting an episode as solved when the task was solved at ANY step
(``success_once``: stricter than the suites' ``success_at_end``). This reads ``gendex eval`` result folders (or
leaderboard result files) of the ``hold`` and ``random`` policies on one suite, prints a row per task, and exits 1
naming every task over the bound.

Run (the runs themselves: ``gendex eval --suite S --policy hold --workers 2 --out OUT/hold``, the same for random)::

    .venv/bin/python benchmarks/suite_calibration.py OUT/hold OUT/random [--bound 5]

A suite of v2 shares its seeds with the other v2 suites, so one run of ``gendex-lib-v2`` covers the tasks of
``gendex-ref-v2`` and ``gendex-skills-v2``; ``--derive SUITE OUT`` writes that suite's episodes from a run into
``OUT/<policy>/episodes.jsonl``, where ``gendex eval --suite SUITE --policy P --out OUT/<policy>`` then finds every
episode done and writes its eval_info.
"""

from __future__ import annotations

# isort: off
import gendex_envs.blas  # noqa: F401  (first: it pins OpenBLAS's kernels before numpy loads)
# isort: on

import argparse
import json
import sys
from pathlib import Path


def load(path: Path) -> dict:
    """eval_info of a result folder, its eval_info.json, or a leaderboard result file."""
    path = path / "eval_info.json" if path.is_dir() else path
    data = json.loads(path.read_text())
    return data.get("eval_info", data)


def per_task(info: dict) -> dict[str, tuple[int, int, int]]:
    """Task -> (episodes, solved at the end, solved at any step), from either eval_info layout."""
    if isinstance(info["per_task"], list):
        return {e["task_id"]: (e["episodes"], e["n_successes"], sum(e["metrics"]["successes_once"]))
                for e in info["per_task"]}
    once: dict[str, int] = {}
    for r in info["per_episode"]:
        once[r["task"]] = once.get(r["task"], 0) + bool(r["success_once"])
    return {t: (d["episodes"], d["successes"], once.get(t, 0)) for t, d in info["per_task"].items()}


def derive(run: Path, suite_name: str, out: Path) -> Path:
    """Copy the episodes of ``suite_name``'s tasks and seeds from the run folder ``run`` into ``out``."""
    from gendex.eval.suite import load_suite

    suite = load_suite(suite_name)
    seeds, tasks = set(suite.seeds()), set(suite.tasks)
    rows = [json.loads(line) for line in (run / "episodes.jsonl").read_text().splitlines() if line.strip()]
    keep = [r for r in rows if r["task"] in tasks and r["seed"] in seeds]
    out.mkdir(parents=True, exist_ok=True)
    (out / "episodes.jsonl").write_text("".join(json.dumps(r) + "\n" for r in keep))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="*", type=Path, help="hold and random result folders (or result files)")
    ap.add_argument("--bound", type=float, default=5.0, help="largest allowed success, percent")
    ap.add_argument("--derive", nargs=2, metavar=("SUITE", "OUT"), help="copy SUITE's episodes of each run to OUT")
    args = ap.parse_args()
    if args.derive:
        for run in args.runs:
            policy = json.loads((run / "eval_run.json").read_text())["policy"]
            print(f"{derive(run, args.derive[0], Path(args.derive[1]) / policy) / 'episodes.jsonl'}")
        return 0
    infos = {load(p)["policy"]: load(p) for p in args.runs}
    suites = {i["suite"]["name"] for i in infos.values()}
    if len(suites) != 1:
        print(f"the runs are of several suites: {sorted(suites)}", file=sys.stderr)
        return 2
    tables = {p: per_task(i) for p, i in infos.items()}
    tasks = list(next(iter(tables.values())))
    over = []
    print(f"suite {suites.pop()}: success at any step / at the end, per policy (bound {args.bound:g} %)\n")
    print("| task | " + " | ".join(tables) + " |\n|---|" + "---|" * len(tables))
    for task in tasks:
        cells = []
        for policy, table in tables.items():
            n, end, once = table.get(task, (0, 0, 0))
            cells.append(f"{once}/{n} ({end} at end)")
            if n and 100.0 * once / n > args.bound:
                over.append(f"{task} ({policy} {once}/{n})")
        print(f"| `{task}` | " + " | ".join(cells) + " |")
    if over:
        print(f"\nover the bound: {', '.join(over)}")
        return 1
    print(f"\nevery task at or under {args.bound:g} % for {', '.join(tables)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
