"""Which CPU-dispatched kernels change a collected episode, and what pinning them (gendex.data.numerics) costs.

Per task, in one run, each in its own worker process (the switches are read when a library loads):

(a) ``--attempts`` seeded attempts (seeds ``--seed`` ..) exactly as a dataset build runs them, with the CPU's own
    kernels ("native"), then with one switch of :data:`gendex.data.numerics.PINNED_ENV` at a time, then with all of
    them ("pinned"): for each, how many attempts recorded other actions, states or outcomes than native. A switch
    that changes nothing here may still matter on another CPU (this machine cannot run AVX-512 kernels).
(b) seconds per attempt native and pinned (the attempts' own time, not the worker's start), and their ratio.
(c) the pinned run once more: it must record the same bytes (0 differing attempts).

Run: ``.venv/bin/python benchmarks/numerics.py [--tasks GenDex/OpenCabinet-v1 ...] [--attempts 6] [--seed S]``.
"""

from __future__ import annotations

import argparse
import functools
import hashlib
import logging
import os
import platform
import statistics
from pathlib import Path

import numpy as np

import gendex_envs  # noqa: F401  (registers the GenDex/* ids)
from gendex.data import numerics
from gendex.data.collector import CollectConfig, _make_attempter
from gendex.fanout import Backend, ordered_map
from gendex.solve import SOLVER_ENV_KWARGS, SOLVERS
from gendex_envs.registry import resolve_task

SINGLE = {  # one switch at a time, as its library would see another CPU
    "torch plain kernels": ("ATEN_CPU_CAPABILITY",),
    "numpy baseline loops": ("NPY_DISABLE_CPU_FEATURES",),
    "OpenBLAS SSE3 kernels": ("OPENBLAS_CORETYPE",),
    "MKL compatible path": ("MKL_CBWR",),
    "oneDNN SSE4.1": ("ONEDNN_MAX_CPU_ISA", "DNNL_MAX_CPU_ISA"),
    "libm without AVX/FMA": ("GLIBC_TUNABLES",),
    "one thread": ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"),
}


def _digest(result) -> str:
    h = hashlib.sha256(f"{result.seed};{result.steps};{result.failure.key if result.failure else 'ok'};".encode())
    if result.episode is not None:
        for name in ("action", "state", "reward", "success", "environment_state"):
            h.update(np.ascontiguousarray(getattr(result.episode, name)).tobytes())
    return h.hexdigest()


def attempts(task: str, seeds: list[int], env: dict[str, str]) -> tuple[list[str], list[float]]:
    cfg = CollectConfig(task_id=task, num_success=len(seeds), out=Path("."), formats=(), seed=seeds[0],
                        **SOLVER_ENV_KWARGS["stages"])
    root = str(resolve_task(task).tasks_root)
    backend = Backend("process", 1, env=tuple(sorted(env.items())))
    results = list(ordered_map(functools.partial(_make_attempter, cfg, SOLVERS["stages"], root), seeds, backend))
    return [_digest(r) for r in results], [r.seconds for r in results]


def manifest_tasks() -> list[str]:
    """The first task of each committed dataset manifest that records checksums (what a build must reproduce)."""
    from gendex.data.datasets import load_manifest
    from gendex_envs.library import library_dir

    manifests = [load_manifest(p.stem) for p in sorted(library_dir("datasets").glob("*.yaml"))]
    return sorted({m.tasks[0].task for m in manifests if m.checksums})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="+", help="env ids (default: the first task of each recorded dataset manifest)")
    ap.add_argument("--attempts", type=int, default=6)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    logging.basicConfig(level=logging.ERROR)
    cpu = next((line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                if line.startswith("model name")), platform.machine())
    print(f"machine: {cpu}, {os.cpu_count()} CPUs; pinned numerics {numerics.NUMERICS}")
    pinned = {k: v for k, v in numerics.PINNED_ENV.items() if k != numerics.MARKER}
    for task in args.tasks or manifest_tasks():
        seeds = list(range(args.seed, args.seed + args.attempts))
        native, t_native = attempts(task, seeds, {})
        print(f"\n{task}, seeds {seeds[0]}..{seeds[-1]}: attempts that differ from native")
        for label, keys in SINGLE.items():
            got, _ = attempts(task, seeds, {k: pinned[k] for k in keys})
            print(f"  {label:24s} {sum(a != b for a, b in zip(got, native, strict=True))}/{len(seeds)}")
        pin, t_pin = attempts(task, seeds, dict(numerics.PINNED_ENV))
        again, _ = attempts(task, seeds, dict(numerics.PINNED_ENV))
        print(f"  {'all pinned':24s} {sum(a != b for a, b in zip(pin, native, strict=True))}/{len(seeds)}")
        changed = sum(a != b for a, b in zip(pin, again, strict=True))
        print(f"  pinned run again: {changed}/{len(seeds)} differ from the first")
        print(f"  s/attempt native {statistics.mean(t_native):.2f}, pinned {statistics.mean(t_pin):.2f}, "
              f"ratio pinned/native {statistics.mean(t_pin) / statistics.mean(t_native):.2f}")


if __name__ == "__main__":
    main()
