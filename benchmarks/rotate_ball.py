"""How hard is RotateTennisBall? Success, final rotation and drop rate of three policies over seeded episodes.

(a) uniform random actions, (b) the scripted finger gait :class:`gendex.solve.in_hand.FingerGaitSolver`,
(c) the task version's trained PPO policy of stage ``rotate_ball``, if it has one.
Every episode runs the whole horizon (seeds 0..N-1, one CPU env, ``pd_joint_delta_pos``, ``control_joint=hand``);
success is the task's (a quarter turn counter-clockwise held 5 steps), a drop is the task's ``fail``.

Run: ``.venv/bin/python benchmarks/rotate_ball.py [--episodes 20]``.
"""

from __future__ import annotations

import argparse
import logging
import math
import time
from collections.abc import Callable

import gymnasium as gym
import numpy as np

import gendex_envs  # noqa: F401  (registers the GenDex/* ids)
from gendex.solve.in_hand import FingerGaitSolver

TASK = "GenDex/RotateTennisBall-v0"
STAGE = "rotate_ball"

log = logging.getLogger("bench.rotate_ball")

Policy = Callable[[gym.Env, object], np.ndarray]
"""(env, obs) -> action; ``reset(env, obs)`` hooks are given separately."""


def episode(env: gym.Env, seed: int, reset: Callable[[gym.Env, object], None], act: Policy) -> dict:
    obs, info = env.reset(seed=seed)
    reset(env, obs)
    succeeded = False
    steps = 0
    while True:
        obs, _, terminated, truncated, info = env.step(act(env, obs))
        steps += 1
        succeeded |= bool(info["success"])
        if terminated or truncated:
            break
    return dict(success=succeeded, dropped=bool(info["fail"]), rotation=float(info["rotation"]), steps=steps)


def evaluate(env: gym.Env, name: str, n: int, reset, act) -> dict:
    t0 = time.perf_counter()
    runs = [episode(env, seed, reset, act) for seed in range(n)]
    wall = time.perf_counter() - t0
    res = dict(policy=name, episodes=n, success=np.mean([r["success"] for r in runs]),
               drop=np.mean([r["dropped"] for r in runs]),
               abs_rot_deg=np.mean([abs(math.degrees(r["rotation"])) for r in runs]),
               rot_deg=np.mean([math.degrees(r["rotation"]) for r in runs]),
               steps_per_s=sum(r["steps"] for r in runs) / wall)
    print(f"{name:12s} success {res['success']:6.1%}  drop {res['drop']:6.1%}  mean final |rotation| "
          f"{res['abs_rot_deg']:6.1f} deg (signed {res['rot_deg']:+6.1f})  {res['steps_per_s']:6.0f} steps/s",
          flush=True)
    return res


def main(argv: list[str] | None = None) -> list[dict]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=20)
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    env = gym.make(TASK, control_mode="pd_joint_delta_pos", control_joint="hand")
    results = []
    try:
        rng = np.random.default_rng(0)
        results.append(evaluate(env, "random", args.episodes, lambda e, o: None,
                                lambda e, o: rng.uniform(-1, 1, e.action_space.shape).astype(np.float32)))
        gait = FingerGaitSolver()
        results.append(evaluate(env, gait.name, args.episodes, gait.reset, gait.act))
        version = env.unwrapped.task
        files = version.policy(STAGE)
        if files is not None:
            from gendex.solve.policy import StagePolicy  # loads SB3: only when there is a policy to run

            policy = StagePolicy.load(version, files)  # applies the saved obs normalization
            results.append(evaluate(env, "ppo", args.episodes, lambda e, o: None, lambda e, o: policy.predict(o)))
        else:
            print(f"ppo          skipped: {version.env_id} has no trained policy of stage {STAGE}")
    finally:
        env.close()
    return results


if __name__ == "__main__":
    main()
