"""What a large task library adds to ``import gendex_envs``: a synthetic root of N versions, with and without its
registration index (:mod:`gendex_envs.task_index`).

The synthetic root holds N copies of one committed version (``--source``, default PutAppleBowl/v0), each under its
own name (``SynthTask0000/v0`` …), so every copy is a distinct task whose spec
parses. ``import gendex_envs`` runs in fresh processes with ``GENDEX_TASKS_PATH`` set to (a) an empty folder, (b) the
synthetic root without an index, (c) the same root with its index; each is timed ``--repeats`` times, alternating,
and the medians are compared. Issue 44's goal: (c) - (a) <= 0.5 s at N = 2 000. Every process also checks that it
registered all N synthetic ids.

Run: ``.venv/bin/python benchmarks/registry_scale.py [--versions 2000] [--repeats 5]``; ``--json PATH`` writes the
record.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CHILD = ("import time; t = time.perf_counter(); import gendex_envs, gymnasium as gym; dt = time.perf_counter() - t; "
         "import json; print(json.dumps({'seconds': dt, 'synthetic': sum(i.startswith('GenDex/SynthTask') "
         "for i in gym.registry)}))")


def synthetic_root(folder: Path, n: int, source: Path) -> Path:
    """``folder`` filled with ``n`` renamed whole copies of the version folder ``source``."""
    from gendex_envs.task_version import TaskLayout, TaskVersion

    version = TaskVersion.at(source)
    for k in range(n):
        name = f"SynthTask{k:04d}"
        spec = TaskLayout(version.copy_to(folder / name / "v0")).spec
        spec.write_text(re.sub(r"(?m)^name: .*$", f"name: {name}", spec.read_text(), count=1))
    return folder


def _import_seconds(tasks_path: Path) -> dict:
    env = {**os.environ, "GENDEX_TASKS_PATH": str(tasks_path)}
    out = subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True, text=True, check=True,
                         cwd=ROOT)
    return json.loads(out.stdout.strip().splitlines()[-1])


def run(versions: int = 2000, repeats: int = 5, source: str = "PutAppleBowl/v0") -> dict:
    from gendex_envs.task_index import write_index

    with tempfile.TemporaryDirectory(prefix="gendex-registry-") as tmp:
        empty = Path(tmp) / "empty"
        empty.mkdir()
        plain = synthetic_root(Path(tmp) / "plain", versions, ROOT / "generated_tasks" / source)
        indexed = Path(tmp) / "indexed"
        shutil.copytree(plain, indexed)
        t = time.perf_counter()
        write_index(indexed)
        index_seconds = time.perf_counter() - t
        times: dict[str, list[float]] = {"empty": [], "no_index": [], "index": []}
        for _ in range(repeats):
            for key, root in (("empty", empty), ("no_index", plain), ("index", indexed)):
                got = _import_seconds(root)
                want = 0 if key == "empty" else versions
                if got["synthetic"] != want:
                    raise SystemExit(f"{key}: registered {got['synthetic']} synthetic ids, expected {want}")
                times[key].append(got["seconds"])
    med = {k: statistics.median(v) for k, v in times.items()}
    return {"versions": versions, "repeats": repeats, "source": source, "median_import_s": med,
            "added_s": {"no_index": med["no_index"] - med["empty"], "index": med["index"] - med["empty"]},
            "all_import_s": times, "write_index_s": index_seconds, "goal_added_s": 0.5,
            "machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                        "load_avg": os.getloadavg()}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--versions", type=int, default=2000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--source", default="PutAppleBowl/v0")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    result = run(args.versions, args.repeats, args.source)
    text = json.dumps(result, indent=1)
    if args.json:
        args.json.write_text(text + "\n")
    sys.stdout.write(text + "\n")


if __name__ == "__main__":
    main()
