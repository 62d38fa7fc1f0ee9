"""What an rgb env's step costs with every sensor camera declared, with only the one a dataset records, and with no
camera (``obs_mode="state"``): ms per step and the ratios, measured in one run (benchmarks/results/collect.md).

    .venv/bin/python benchmarks/sensor_cost.py [--task GenDex/PutAppleBowl-v1] [--resolution 96] [--steps 60]
"""

from __future__ import annotations

# isort: off
import gendex_envs.blas  # first: it pins OpenBLAS's kernels before anything loads numpy
# isort: on

import argparse
import json
import time

import gymnasium as gym
import numpy as np

import gendex_envs  # noqa: F401  (registers the tasks)


def ms_per_step(task: str, steps: int, **kwargs) -> float:
    env = gym.make(task, **kwargs)
    try:
        env.reset(seed=0)
        hold = np.zeros(env.action_space.shape, np.float32)
        for _ in range(5):
            env.step(hold)
        t0 = time.perf_counter()
        for _ in range(steps):
            env.step(hold)
        return (time.perf_counter() - t0) / steps * 1000
    finally:
        env.close()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--task", default="GenDex/PutAppleBowl-v1")
    ap.add_argument("--resolution", type=int, default=96)
    ap.add_argument("--steps", type=int, default=60)
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    rgb = {"obs_mode": "rgb", "sensor_resolution": args.resolution}
    runs: dict[str, list[float]] = {"every camera": [], "left_overhead only": [], "no camera (state)": []}
    for _ in range(args.repeats):  # interleaved, so a busy moment hits each setting alike
        runs["every camera"].append(ms_per_step(args.task, args.steps, **rgb))
        runs["left_overhead only"].append(ms_per_step(args.task, args.steps, **rgb, sensors=["left_overhead"]))
        runs["no camera (state)"].append(ms_per_step(args.task, args.steps, obs_mode="state"))
    best = {k: min(v) for k, v in runs.items()}
    print(json.dumps({"task": args.task, "resolution": args.resolution, "ms_per_step": runs,
                      "ratio_every_to_one": round(best["every camera"] / best["left_overhead only"], 2),
                      "ratio_one_to_state": round(best["left_overhead only"] / best["no camera (state)"], 2)},
                     indent=1))


if __name__ == "__main__":
    main()
