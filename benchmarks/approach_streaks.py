"""How long does a policy keep its fingers at the handle before a task's end state holds?

For each episode: the first step at which the task succeeds, and for each probe (a list of success conditions, JSON)
the longest run of consecutive control steps in which it held before then. This measured why random actions solved
the single-part articulated tasks (their end state came without the fingers at the handle) and sized
``generator.steps.approach`` (record: benchmarks/results/benchmark.md, session 48). One JSON line per episode.

Run::

    .venv/bin/python benchmarks/approach_streaks.py GenDex/CloseCabinet-v3 --policy random --seed 900000 \\
        --episodes 50 --probe '[{"type": "fingertips_near", "object": "cabinet", "part": "handle", "max_dist_m": 0.2}]'

``--policy oracle`` runs the planning executor past success to the time limit (its streak is read before success).
"""

from __future__ import annotations

# isort: off
import gendex_envs.blas
# isort: on

import argparse
import json
import sys
import time

import gendex_envs  # noqa: F401  (registers the GenDex/* ids)
from gendex.eval.policies import resolve_policy
from gendex.eval.runner import make_eval_env
from gendex_envs.spec import ConditionSpec
from gendex_envs.success import conditions_hold


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("task")
    ap.add_argument("--policy", default="random", help="random, hold, oracle or module:factory")
    ap.add_argument("--seed", type=int, default=900_000)
    ap.add_argument("--episodes", type=int, default=50)
    ap.add_argument("--probe", action="append", required=True, help="JSON list of conditions (repeatable)")
    args = ap.parse_args(argv)
    probes = [tuple(ConditionSpec(**c) for c in json.loads(p)) for p in args.probe]
    env = make_eval_env(args.task)
    u = env.unwrapped
    policy = resolve_policy(args.policy)()
    policy.bind(env)
    for seed in range(args.seed, args.seed + args.episodes):
        t0 = time.time()
        obs, info = env.reset(seed=seed)
        policy.reset()
        streak, best = [0] * len(probes), [0] * len(probes)
        first, before = None, None
        for step in range(u.task_spec.max_episode_steps):
            obs, _, term, trunc, info = env.step(policy.act(obs))
            for i, probe in enumerate(probes):
                streak[i] = streak[i] + 1 if bool(conditions_hold(u, probe)[0]) else 0
                best[i] = max(best[i], streak[i])
            if first is None and bool(info["success"]):
                first, before = step, list(best)
                if args.policy != "oracle":
                    break
            if term or trunc:
                break
        sys.stdout.write(json.dumps({"task": args.task, "policy": args.policy, "seed": seed, "success_step": first,
                                     "streak_before": before, "best": best, "s": round(time.time() - t0, 1)}) + "\n")
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
