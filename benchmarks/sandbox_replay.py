"""Does an untrusted copy of a task behave exactly as the committed task, and how much of it replays in process?

For each sampled task version (and each of its stage envs), an untrusted copy of the folder under a temporary task
root (its reward modules run in the sandbox: recorded by the confined worker, replayed in this process,
:mod:`gendex_envs.sandbox.replay`) and the committed version (trusted, in process) take the same random actions
from the same seed. Every step's reward, observation, terminated/truncated and info must be bit-identical. Per
reward function it reports calls replayed in process and calls the worker served (recordings, audits and misses).

Run: ``.venv/bin/python benchmarks/sandbox_replay.py [--sample 20] [--seed 0] [--steps 40] [--stages]``
(``--all`` for every version). Exit status 1 when any step differs.
"""

from __future__ import annotations

# isort: off
import gendex_envs.blas  # first: it pins OpenBLAS's kernels before numpy loads)
# isort: on

import argparse
import random
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

import gendex_envs  # noqa: F401  (registers the GenDex/* ids)
from gendex_envs.errors import StageError
from gendex_envs.registry import make_env, registered_tasks
from gendex_envs.sandbox import host


def _same(a, b) -> bool:
    if isinstance(a, torch.Tensor) or isinstance(b, torch.Tensor):
        return (isinstance(a, torch.Tensor) and isinstance(b, torch.Tensor) and a.dtype == b.dtype
                and a.shape == b.shape and bool(torch.equal(a.cpu(), b.cpu()) or
                                               (a.is_floating_point() and torch.equal(a.isnan(), b.isnan()) and
                                                torch.equal(a.nan_to_num(), b.nan_to_num()))))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)
    if isinstance(a, dict) and isinstance(b, dict):
        return list(a) == list(b) and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    return a == b


def _remote_modules(env) -> list[host.RemoteModule]:
    module = env.unwrapped.judge.module
    out = []
    for fn in (module.evaluate, module.compute_dense_reward, module.get_obs_extra):
        for cell in getattr(fn, "__closure__", None) or ():
            if isinstance(cell.cell_contents, host.RemoteModule) and cell.cell_contents not in out:
                out.append(cell.cell_contents)
    return out


def compare(version, copy: Path, stage, steps: int, seed: int) -> tuple[int, dict, dict]:
    kwargs = {"control_mode": "pd_joint_delta_pos"} if stage is None else {"stage": stage}
    trusted, untrusted = make_env(version.root, **kwargs), make_env(copy, **kwargs)
    differing = 0
    try:
        first = [e.reset(seed=seed) for e in (trusted, untrusted)]
        differing += not _same(first[0], first[1])
        rng = np.random.default_rng(seed)
        low, high = trusted.action_space.low, trusted.action_space.high
        for _ in range(steps):
            action = rng.uniform(low, high).astype(trusted.action_space.dtype)
            a, b = trusted.step(action), untrusted.step(action)
            differing += not _same(a, b)
            if a[2] or a[3]:
                trusted.reset(seed=seed + 1)
                untrusted.reset(seed=seed + 1)
        replayed, served = {}, {}
        for m in _remote_modules(untrusted):
            for fn, n in m.replays.items():
                replayed[fn] = replayed.get(fn, 0) + n
            for fn, n in m.worker_calls.items():
                served[fn] = served.get(fn, 0) + n
        return differing, replayed, served
    finally:
        trusted.close()
        untrusted.close()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sample", type=int, default=20, help="task versions drawn at random")
    ap.add_argument("--all", action="store_true", help="every registered version")
    ap.add_argument("--seed", type=int, default=0, help="draws the sample and seeds the episodes")
    ap.add_argument("--steps", type=int, default=40)
    ap.add_argument("--stages", action="store_true", help="also every stage env of each version")
    args = ap.parse_args()
    versions = [v for _, v in sorted(registered_tasks().items())]
    if not args.all:
        versions = random.Random(args.seed).sample(versions, min(args.sample, len(versions)))
    total_diff, totals_r, totals_s = 0, 0, 0
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="gendex_replay_") as tmp:
        for version in versions:
            copy = Path(tmp) / "tasks" / version.name / version.root.name
            version.copy_to(copy)
            stages = [None] + (list(range(len(version.spec.stages))) if args.stages else [])
            for stage in stages:
                try:
                    diff, replayed, served = compare(version, copy, stage, args.steps, args.seed)
                except StageError as exc:  # a later stage without recorded start states cannot run on its own
                    print(f"{version.env_id} stage {stage}: skipped ({str(exc)[:80]}...)")
                    continue
                total_diff += diff
                totals_r += sum(replayed.values())
                totals_s += sum(served.values())
                where = version.env_id + ("" if stage is None else f" stage {stage}")
                calls = "  ".join(f"{fn}: {replayed.get(fn, 0)}/{replayed.get(fn, 0) + served.get(fn, 0)}"
                                  for fn in sorted(set(replayed) | set(served)))
                print(f"{where:58s} {'same' if diff == 0 else f'{diff} STEPS DIFFER':>16s}   replayed {calls}",
                      flush=True)
    share = totals_r / max(1, totals_r + totals_s)
    print(f"\n{len(versions)} versions, {args.steps} steps each: {total_diff} differing steps; "
          f"{totals_r} of {totals_r + totals_s} reward calls replayed in process ({share:.1%}); "
          f"{time.perf_counter() - start:.0f} s")
    return 1 if total_diff else 0


if __name__ == "__main__":
    sys.exit(main())
