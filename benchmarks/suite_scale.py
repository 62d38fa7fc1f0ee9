"""Does the default test suite's cost grow with the task library? (issue 44, item 3: flat within 10 % when the
library doubles.)

Two clones of the checkout's HEAD are made side by side: one as it is, one whose library is ``--factor`` times as
large. Each task of the doubled clone gets ``factor - 1`` twins (``<Name>Twin``, ``<Name>Twin2`` …): whole copies of
every one of its versions, renamed in their spec, packed into the clone's task store, indexed and recorded as trusted,
then committed, and the clone's ``origin/main`` is moved to that commit, so the twins are part of the library the
suite starts from (a change that touches versions checks those; this measures the steady state). Both clones share
the checkout's ``.venv`` (a link; ``PYTHONPATH`` points every process at its own clone's code and library).

``bash scripts/test.sh --junitxml=…`` then runs in each clone (one after the other, or with ``--together`` both at
once), and the per-test CPU seconds (``benchmarks/cpu_per_test.py``), CPU and wall seconds of each suite, summed test
seconds by file and outcome counts are compared. Wall seconds on this shared 2-core machine drift (the same clone ran
32 % slower forty minutes later) and, run together, single tests took 5 to 20 times longer in one suite than in the
other. CPU seconds drift less but still do (13 % between two sequential runs: oversubscribed cores do the same work
in more CPU time), so the measure of growth is each test's CPU against the median ratio over all tests
(:func:`cpu_changes`): a test whose cost grows with the library stands out above that common drift. Each clone gets
a fresh, empty ``GENDEX_CACHE`` (as a new CI machine has), so caches built by one run do not serve the other; a
twin's instruction is its original's, so the doubled clone embeds no more distinct instructions than the base
(:mod:`generator.embedding` encodes a new instruction once a machine, ~0.2 CPU s under load).

Run: ``.venv/bin/python benchmarks/suite_scale.py [--factor 2] [--together] [--workdir DIR] [--json PATH]`` (about
twice the suite's time either way). ``--prepare-only`` makes the clones and stops.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import platform
import shutil
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

TWIN_SCRIPT = """
import json, re, sys
from pathlib import Path
from gendex_envs.registry import discover_tasks
from gendex_envs.task_version import TaskLayout

root, factor = Path(sys.argv[1]), int(sys.argv[2])
made = []
for env_id, version in sorted(discover_tasks([root]).items()):
    for k in range(1, factor):
        name = version.name + ("Twin" if k == 1 else f"Twin{k}")
        dest = root / name / version.root.name
        spec = TaskLayout(version.copy_to(dest)).spec
        spec.write_text(re.sub(r"(?m)^name: .*$", f"name: {name}", spec.read_text(), count=1))
        made.append(str(dest))
print(json.dumps(made))
"""


def _run(cmd: list[str], cwd: Path, env: dict | None = None) -> str:
    out = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True)
    if out.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed in {cwd}:\n{out.stdout[-3000:]}\n{out.stderr[-3000:]}")
    return out.stdout


def _env(clone: Path) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "GENDEX_TASKS_PATH"}
    env["PYTHONPATH"] = str(clone)
    env["GENDEX_CACHE"] = str(clone.parent / f"{clone.name}-cache")
    return env


def make_clone(dest: Path, factor: int) -> dict:
    """A clone of HEAD at ``dest`` whose library is ``factor`` times the checkout's, committed (see the module)."""
    if dest.exists():
        shutil.rmtree(dest)
    _run(["git", "clone", "--quiet", str(ROOT), str(dest)], ROOT)
    (dest / ".venv").symlink_to(ROOT / ".venv")
    py, env = str(ROOT / ".venv" / "bin" / "python"), _env(dest)
    twins: list[str] = []
    if factor > 1:
        twins = json.loads(_run([py, "-c", TWIN_SCRIPT, str(dest / "generated_tasks"), str(factor)], dest, env))
        for cmd in (["store", "pack"], ["store", "index"], ["trust", *twins]):
            _run([py, "-m", "gendex.cli", *cmd], dest, env)
        _run(["git", "add", "generated_tasks"], dest)
        _run(["git", "-c", "user.name=suite-scale", "-c", "user.email=suite-scale@localhost", "commit", "--quiet",
              "-m", f"synthetic library: {factor}x the tasks"], dest)
    _run(["git", "update-ref", "refs/remotes/origin/main", "HEAD"], dest)
    ids = _run([py, "-c", "import gymnasium as gym, gendex_envs; "
                          "print(sum(i.startswith('GenDex/') for i in gym.registry))"], dest, env)
    return {"path": str(dest), "factor": factor, "twin_versions": len(twins), "registered": int(ids.strip())}


def start_suite(clone: Path, junit: Path) -> tuple[subprocess.Popen, float]:
    """``scripts/test.sh`` started in ``clone`` (with a fresh cache folder), and when it started."""
    env = _env(clone)
    shutil.rmtree(env["GENDEX_CACHE"], ignore_errors=True)
    env["PYTHONPATH"] += os.pathsep + str(clone / "benchmarks")  # the per-test CPU plugin
    env["GENDEX_CPU_JSON"] = str(junit.with_suffix(".cpu"))
    for old in junit.parent.glob(junit.with_suffix(".cpu").name + ".*.json"):
        old.unlink()
    with open(junit.with_suffix(".log"), "w") as log:
        proc = subprocess.Popen(["bash", "scripts/test.sh", f"--junitxml={junit}", "-q", "-p", "no:cacheprovider",
                                 "-p", "cpu_per_test"], cwd=clone, env=env, stdout=log, stderr=subprocess.STDOUT)
    return proc, time.perf_counter()


def finish_suite(proc: subprocess.Popen, started: float, junit: Path) -> dict:
    """Wall seconds, CPU seconds, outcome counts and test seconds by file of a suite :func:`start_suite` started.

    CPU seconds: user + system of the suite's process tree (pytest and the workers and children it waited for, from
    ``wait4``); per test, from the ``cpu_per_test`` plugin's files. Wall seconds say what a user waits."""
    _, status, usage = os.wait4(proc.pid, 0)
    cpu_by_test: dict[str, float] = {}
    for part in junit.parent.glob(junit.with_suffix(".cpu").name + ".*.json"):
        cpu_by_test.update(json.loads(part.read_text()))
    proc.returncode = os.waitstatus_to_exitcode(status)
    wall = time.perf_counter() - started
    counts: collections.Counter = collections.Counter()
    by_file: collections.Counter = collections.Counter()
    failed = []
    for case in ET.parse(junit).iter("testcase"):
        by_file[case.get("classname")] += float(case.get("time", 0))
        kind = next((c.tag for c in case if c.tag in ("failure", "error", "skipped")), "passed")
        counts[kind] += 1
        if kind in ("failure", "error"):
            failed.append(f"{case.get('classname')}::{case.get('name')}")
    return {"wall_s": wall, "cpu_s": usage.ru_utime + usage.ru_stime, "cpu_by_test_s": cpu_by_test,
            "returncode": proc.returncode,
            "counts": dict(counts), "failed": failed, "test_s": sum(by_file.values()),
            "by_file_s": dict(by_file.most_common()), "tail": junit.with_suffix(".log").read_text()[-1500:]}


def cpu_changes(base: dict, big: dict, top: int = 15) -> dict:
    """Per-test CPU seconds of two suites compared. Even CPU seconds drift with the machine's load (oversubscribed
    cores run the same work in more CPU time), so besides the sums this gives the median ratio over the tests of at
    least 1 CPU s (the drift common to all tests) and each test's excess over it: a test whose cost grows with the
    library stands out there."""
    import statistics

    a, b = base["cpu_by_test_s"], big["cpu_by_test_s"]
    both = set(a) & set(b)
    total_a, total_b = sum(a[t] for t in both), sum(b[t] for t in both)
    ratios = [b[t] / a[t] for t in both if a[t] >= 1.0]
    drift = statistics.median(ratios) if ratios else 1.0
    excess = {t: b[t] - drift * a[t] for t in both}
    ranked = sorted(both, key=lambda t: -excess[t])
    return {"per_test_cpu": {"tests": len(both), "base_s": round(total_a, 1), "big_s": round(total_b, 1),
                             "ratio": total_b / total_a if total_a else None, "median_ratio": drift,
                             "positive_excess_s": round(sum(max(0.0, e) for e in excess.values()), 1),
                             "only_in_one": len(set(a) ^ set(b))},
            "largest_cpu_excess_s": {t: {"base": round(a[t], 1), "big": round(b[t], 1),
                                         "excess": round(excess[t], 1)} for t in ranked[:top]}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--factor", type=int, default=2)
    ap.add_argument("--workdir", type=Path, default=Path("/tmp/gendex-suite-scale"))
    ap.add_argument("--json", type=Path)
    ap.add_argument("--prepare-only", action="store_true")
    ap.add_argument("--together", action="store_true", help="run both suites at the same time (a paired ratio)")
    args = ap.parse_args()
    if args.factor < 2:
        raise SystemExit(f"--factor must be at least 2 (got {args.factor})")
    head = _run(["git", "rev-parse", "HEAD"], ROOT).strip()
    clones = {"base": make_clone(args.workdir / "base", 1),
              f"x{args.factor}": make_clone(args.workdir / f"x{args.factor}", args.factor)}
    print(json.dumps(clones, indent=1), flush=True)
    if args.prepare_only:
        return
    runs, load_before = {}, os.getloadavg()
    if args.together:
        started = {key: start_suite(Path(info["path"]), args.workdir / f"{key}.xml") for key, info in clones.items()}
        for key, (proc, t0) in started.items():
            runs[key] = finish_suite(proc, t0, args.workdir / f"{key}.xml")
    else:
        for key, info in clones.items():
            runs[key] = finish_suite(*start_suite(Path(info["path"]), args.workdir / f"{key}.xml"),
                                     args.workdir / f"{key}.xml")
    for key, run in runs.items():
        print(key, json.dumps({k: v for k, v in run.items() if not k.startswith(("by_", "cpu_by"))}), flush=True)
    base, big = runs["base"], runs[f"x{args.factor}"]
    record = {"commit": head, "factor": args.factor, "together": args.together, "clones": clones, "runs": runs,
              "cpu_ratio": big["cpu_s"] / base["cpu_s"], "wall_ratio": big["wall_s"] / base["wall_s"],
              "test_time_ratio": big["test_s"] / base["test_s"], **cpu_changes(base, big),
              "machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                          "load_avg_before": load_before, "load_avg_after": os.getloadavg()}}
    keys = ("cpu_ratio", "wall_ratio", "test_time_ratio", "per_test_cpu", "largest_cpu_excess_s")
    print(json.dumps({k: record[k] for k in keys}, indent=1))
    if args.json:
        args.json.write_text(json.dumps(record, indent=1) + "\n")


if __name__ == "__main__":
    sys.exit(main())
