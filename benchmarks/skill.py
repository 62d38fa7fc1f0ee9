"""Does a skill's task need the skill? The dexterous-skills issue's check, per task, on seeds nobody looked at.

Per task (``--tasks``: env ids, or ``--skill``: every registered task whose task skills include it), on ``--seeds``
new seeds (``--seed`` ..):

- the stage executor's success rate (the solvability gate's measurement, :func:`generator.steps.gate.measure`);
- holding every joint still, and uniform random joint-delta actions, for the whole episode: success at any step
  (the measure most favourable to them);
- a blind replay: the first success the executor finds from ``--source-seed`` on, its actions replayed open-loop on
  the same new seeds (success at any step).

The issue's goal: solver >= 80 %, hold and random <= 5 %, blind replay <= 10 %.

Run: ``.venv/bin/python benchmarks/skill.py --skill press [--seeds 50] [--seed 61000] [--workers 2]``.
"""

from __future__ import annotations

# isort: off
import gendex_envs.blas  # noqa: F401  (first: it pins OpenBLAS's kernels before numpy loads)
# isort: on

import argparse
import logging
import multiprocessing as mp
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from blind_replay import _success  # the same success reading as the blind replay


def baseline(env, seed: int, policy: str) -> bool:
    """Success at any step of a whole episode of holding still (``hold``) or uniform random actions (``random``)."""
    _, _ = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    space = env.action_space
    for _ in range(env.unwrapped.task_spec.max_episode_steps):
        a = np.zeros(space.shape, np.float32) if policy == "hold" else rng.uniform(space.low, space.high)
        _, _, terminated, truncated, info = env.step(a.astype(np.float32))
        if _success(info):
            return True
        if terminated or truncated:
            break
    return False


def one_task(job: tuple[str, list[int], int]) -> dict:
    env_id, seeds, source_seed = job
    import gymnasium as gym
    from blind_replay import replay, solve

    from gendex.solve import SOLVER_ENV_KWARGS
    from gendex_envs.registry import resolve_task
    from generator.steps.gate import measure

    t0 = time.perf_counter()
    version = resolve_task(env_id)
    solver = measure(version.root, seeds=seeds)
    out = {"task": env_id, "solver": solver.successes, "seeds": len(seeds)}
    delta = gym.make(env_id, **SOLVER_ENV_KWARGS["hold"])
    try:
        for policy in ("hold", "random"):
            out[policy] = sum(baseline(delta, s, policy) for s in seeds)
    finally:
        delta.close()
    env = gym.make(env_id, **SOLVER_ENV_KWARGS["stages"])
    try:
        actions, source = None, source_seed
        while actions is None and source < source_seed + 10:
            actions = solve(env, source)
            source += 1
        out["blind"] = None if actions is None else sum(replay(env, s, actions) for s in seeds)
    finally:
        env.close()
    out["seconds"] = round(time.perf_counter() - t0)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="*", help="env ids")
    ap.add_argument("--skill", help="every registered task (latest version) whose task skills include this one")
    ap.add_argument("--seeds", type=int, default=50)
    ap.add_argument("--seed", type=int, default=61000)
    ap.add_argument("--source-seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    logging.basicConfig(level=logging.ERROR)
    tasks = list(args.tasks or [])
    if args.skill:
        import gendex_envs  # noqa: F401  (registers the GenDex/* ids)
        from gendex_envs.registry import registered_tasks
        from generator.stats import latest_versions, task_skills

        tasks += sorted(i for i, v in latest_versions(registered_tasks()).items() if args.skill in task_skills(v.spec))
    if not tasks:
        raise SystemExit("no tasks: give --tasks or a --skill some registered task has")
    seeds = list(range(args.seed, args.seed + args.seeds))
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs; seeds {seeds[0]}.."
          f"{seeds[-1]}; {len(tasks)} tasks")
    print("| task | solver | hold | random | blind replay | s |\n|---|---|---|---|---|---|")
    with mp.get_context("spawn").Pool(args.workers) as pool:
        for r in pool.imap(one_task, [(t, seeds, args.source_seed) for t in tasks]):
            n = r["seeds"]
            blind = "no success to replay" if r["blind"] is None else f"{r['blind']}/{n}"
            print(f"| {r['task']} | {r['solver']}/{n} | {r['hold']}/{n} | {r['random']}/{n} | {blind} | "
                  f"{r['seconds']} |", flush=True)


if __name__ == "__main__":
    main()
