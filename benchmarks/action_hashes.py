"""Has the stage executor's behaviour changed? Hash what it does on a sample of task versions, under two checkouts,
and compare.

Per version and seed: one attempt of the stage executor exactly as collection runs it (a history-free env with the
solver's action space), hashing every action, observation and reward it produces (SHA-256, first 16 hex digits),
with the attempt's outcome and length. Run it under the old code and the new (a ``git worktree`` of the old commit
with ``PYTHONPATH`` set to it) and compare the two JSON files: equal files mean the same behaviour, bit for bit.

Run: ``.venv/bin/python benchmarks/action_hashes.py --sample 9 --sample-seed 881 --seeds 991000 991001 --json
new.json`` (the reference tasks' newest versions plus 9 versions drawn with the seed), or ``--tasks ID ...``;
``--compare old.json new.json`` prints the differences (exit 1 if any).
"""

from __future__ import annotations

# isort: off
import gendex_envs.blas  # noqa: F401  (first: it pins OpenBLAS's kernels before numpy loads)
# isort: on

import argparse
import hashlib
import json
import random
import sys
from pathlib import Path

import numpy as np


def choose(tasks: list[str] | None, sample: int, seed: int) -> list[str]:
    """``tasks`` as given, or the newest version of each reference task and ``sample`` more drawn with ``seed``."""
    import gymnasium as gym

    import gendex_envs  # noqa: F401  (registers the GenDex ids)
    from gendex_envs.registry import REFERENCE_TASKS, resolve_task

    if tasks:
        return [resolve_task(t).env_id for t in tasks]
    ids = sorted(i for i in gym.registry if i.startswith("GenDex/"))
    ref = [resolve_task(n).env_id for n in REFERENCE_TASKS]
    rest = [i for i in ids if i not in ref]
    return ref + random.Random(seed).sample(rest, min(sample, len(rest)))


def hash_attempts(ids: list[str], seeds: list[int]) -> dict[str, list]:
    from gendex.solve import SOLVER_ENV_KWARGS, SOLVERS
    from gendex.solve.attempt import run_attempt
    from gendex_envs.registry import HISTORY_FREE, make_env, resolve_task

    out: dict[str, list] = {}
    for env_id in ids:
        env = make_env(resolve_task(env_id), **HISTORY_FREE, **SOLVER_ENV_KWARGS["stages"])
        try:
            for seed in seeds:
                h = hashlib.sha256()
                step = env.step

                def hashed(action, step=step, h=h):
                    r = step(action)
                    h.update(np.asarray(action, dtype=np.float32).tobytes())
                    h.update(np.asarray(r[0], dtype=np.float32).tobytes())
                    h.update(np.asarray(r[1], dtype=np.float64).tobytes())
                    return r

                env.step = hashed  # the attempt steps through the instance attribute, old code and new alike
                try:
                    res = run_attempt(env, SOLVERS["stages"](), seed)
                finally:
                    env.step = step
                out[f"{env_id}:{seed}"] = [bool(res.succeeded), int(res.steps), h.hexdigest()[:16]]
                print(env_id, seed, out[f"{env_id}:{seed}"], flush=True)
        finally:
            env.close()
    return out


def compare(old: Path, new: Path) -> int:
    a, b = json.loads(old.read_text()), json.loads(new.read_text())
    differ = sorted(k for k in a.keys() | b.keys() if a.get(k) != b.get(k))
    for k in differ:
        print(f"{k}: {a.get(k)} -> {b.get(k)}")
    print(f"{len(a.keys() & b.keys())} attempts in both, {len(differ)} differ")
    return 1 if differ else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tasks", nargs="+")
    ap.add_argument("--sample", type=int, default=9)
    ap.add_argument("--sample-seed", type=int, default=881)
    ap.add_argument("--seeds", type=int, nargs="+", default=[991000, 991001])
    ap.add_argument("--json", type=Path)
    ap.add_argument("--compare", type=Path, nargs=2, metavar=("OLD", "NEW"))
    args = ap.parse_args()
    if args.compare:
        return compare(*args.compare)
    out = hash_attempts(choose(args.tasks, args.sample, args.sample_seed), args.seeds)
    if args.json:
        args.json.write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
