"""Does a task's randomization defeat a blind policy? Replay one recorded success open-loop on new seeds.

Per task: the stage executor solves the first seed from ``--source-seed`` on that it succeeds on; its actions are then
replayed unchanged (no observation, no feedback) after resets with ``--seeds`` new seeds (``--seed`` ..). A replay
counts as a success when the task's success is reported at any step (``success_once``, the measure most favourable
to the blind policy). A benchmark or a dataset whose variation a blind replay wins teaches nothing; the issue's goal is
<= 10 % on every reference task, while the solver itself stays >= 95 % (``benchmarks/collect.py``).

With ``--solver`` the executor is also run on the same new seeds, to show that the seeds are solvable when looked at.

Run: ``.venv/bin/python benchmarks/blind_replay.py [--tasks GenDex/PutAppleBowl-v1 ...] [--seeds 20]``.
"""

from __future__ import annotations

import argparse
import logging
import os
import platform
import time

# isort: off
import gendex_envs.blas  # first: it pins OpenBLAS's kernels before numpy loads
# isort: on

import gymnasium as gym
import numpy as np

import gendex_envs  # noqa: F401  (registers the GenDex/* ids)
from gendex.solve import SOLVER_ENV_KWARGS, SOLVERS
from gendex_envs.errors import ExecutionError
from gendex_envs.registry import REFERENCE_TASKS, resolve_task


def _success(info: dict) -> bool:
    value = info.get("success", False)
    return bool(np.asarray(value.cpu() if hasattr(value, "cpu") else value).reshape(-1)[0])


def solve(env: gym.Env, seed: int) -> np.ndarray | None:
    """The actions of the stage executor's episode on ``seed`` if it succeeds, else None."""
    solver = SOLVERS["stages"]()
    obs, info = env.reset(seed=seed)
    solver.reset(env, obs)
    actions = []
    while True:
        try:
            action = solver.act(env, obs)
        except ExecutionError:
            return None
        if action is None:
            break
        actions.append(np.asarray(action, dtype=np.float32))
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            break
    return np.stack(actions) if actions and _success(info) else None


def replay(env: gym.Env, seed: int, actions: np.ndarray) -> bool:
    """success_once of ``actions`` stepped open-loop after a reset with ``seed``."""
    env.reset(seed=seed)
    for a in actions:
        _, _, terminated, truncated, info = env.step(a)
        if _success(info):
            return True
        if truncated:
            break
    return False


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="+", help="env ids (default: the newest version of each reference task)")
    ap.add_argument("--source-seed", type=int, default=0, help="first seed tried for the recorded success")
    ap.add_argument("--seeds", type=int, default=20, help="new seeds to replay on")
    ap.add_argument("--seed", type=int, default=9000, help="first new seed")
    ap.add_argument("--solver", action="store_true", help="also run the solver on the new seeds")
    args = ap.parse_args()
    logging.basicConfig(level=logging.ERROR)
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs; seeds "
          f"{args.seed}..{args.seed + args.seeds - 1}")
    worst = 0.0
    for task in args.tasks or [resolve_task(name).env_id for name in REFERENCE_TASKS]:
        t0 = time.perf_counter()
        env = gym.make(task, **SOLVER_ENV_KWARGS["stages"])
        source, actions = args.source_seed, None
        while actions is None and source < args.source_seed + 10:
            actions = solve(env, source)
            source += 1
        if actions is None:
            print(f"{task}: the solver found no success on seeds {args.source_seed}..{source - 1}; nothing to replay")
            worst = 1.0
            env.close()
            continue
        seeds = range(args.seed, args.seed + args.seeds)
        wins = sum(replay(env, s, actions) for s in seeds)
        line = (f"{task}: blind replay of seed {source - 1}'s success ({len(actions)} actions): "
                f"{wins}/{args.seeds} = {100 * wins / args.seeds:.0f} %")
        if args.solver:
            solved = sum(solve(env, s) is not None for s in seeds)
            line += f"; the solver on the same seeds: {solved}/{args.seeds}"
        print(f"{line}  ({time.perf_counter() - t0:.0f} s)", flush=True)
        worst = max(worst, wins / args.seeds)
        env.close()
    print(f"\nworst blind replay {100 * worst:.0f} % (goal <= 10 %)")


if __name__ == "__main__":
    main()
