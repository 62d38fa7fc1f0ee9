"""How hard is RotateTennisBall, and why do attempts fail? Success, failure kinds and rotation over time per policy.

Policies (``--policies``, default all):

* ``random``: uniform random actions;
* ``gait``: the scripted finger gait :class:`gendex.solve.in_hand.FingerGaitSolver` (open loop);
* ``ppo``: the task version's trained policy of stage ``rotate_ball``, deterministic (its mean action, as its training
  evaluation and the stage executor run it);
* ``ppo-stochastic``: the same policy sampling its Gaussian actions (as during training);
* ``executor``: the stage executor running the task as ``gendex collect`` does (``pd_joint_pos``, every joint, the
  policy turned into absolute targets), episodes ending at the task's success.

The first four run on the stage's own env (``pd_joint_delta_pos``, ``control_joint=hand``) until the task's success,
a drop or the horizon. Every attempt falls in one kind:

* ``success``: the quarter turn held 5 steps (the task's success) at some step;
* ``drop``: the ball left the palm (the reward module's ``fail``) before any success;
* ``short``: the ball never turned 90 degrees counter-clockwise (a stall or too slow);
* ``lost``: it did turn 90 degrees but did not hold it 5 steps (rolled back, or spun on past 180 degrees, where the
  wrapped twist reads negative).

Run: ``.venv/bin/python benchmarks/rotate_ball.py [--task GenDex/RotateTennisBall-v0] [--episodes 20] [--seed 0]
[--policies ppo executor] [--traces out.json]`` (``--traces``: every attempt's rotation per step, degrees).
Envs are made with :data:`~gendex_envs.registry.HISTORY_FREE` (as ``gendex collect`` makes them): an attempt
depends only on its seed, not on the attempts run before it.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path

# isort: off
import gendex_envs.blas  # first: it pins OpenBLAS's kernels before numpy loads
# isort: on

import gymnasium as gym
import numpy as np

import gendex_envs  # noqa: F401  (registers the GenDex/* ids)
from gendex.solve.in_hand import FingerGaitSolver
from gendex_envs.registry import HISTORY_FREE

TASK = "GenDex/RotateTennisBall-v0"
STAGE = "rotate_ball"
TARGET_DEG = 90.0
POLICIES = ("random", "gait", "ppo", "ppo-stochastic", "executor")
KINDS = ("success", "drop", "short", "lost")

log = logging.getLogger("bench.rotate_ball")

Act = Callable[[gym.Env, object], np.ndarray]
"""(env, obs) -> action."""


def kind_of(success: bool, dropped: bool, rotation_deg: list[float]) -> str:
    """The failure kind of an attempt (module doc)."""
    if success:
        return "success"
    if dropped:
        return "drop"
    return "lost" if rotation_deg and max(rotation_deg) >= TARGET_DEG else "short"


def stage_episode(env: gym.Env, seed: int, reset: Callable[[gym.Env, object], None], act: Act) -> dict:
    """One whole-horizon episode on the stage env."""
    obs, info = env.reset(seed=seed)
    reset(env, obs)
    first, rotation = None, []
    while True:
        obs, _, terminated, truncated, info = env.step(act(env, obs))
        rotation.append(math.degrees(float(info["rotation"])))
        if first is None and bool(info["success"]):
            first = len(rotation)
        if terminated or truncated:
            break
    return dict(seed=seed, success_step=first, dropped=bool(info["fail"]) and first is None, rotation=rotation)


def executor_episode(env: gym.Env, seed: int, executor) -> dict:
    """One attempt of the stage executor, as ``gendex collect`` runs it."""
    from gendex.episode_loop import Hooks
    from gendex.solve.attempt import run_attempt

    rotation: list[float] = []
    dropped = [False]

    def watch(step) -> None:
        rotation.append(math.degrees(float(step.info["rotation"])))
        dropped[0] |= bool(step.info["fail"])

    outcome = run_attempt(env, executor, seed, Hooks(on_step=watch))
    return dict(seed=seed, success_step=outcome.steps if outcome.succeeded else None,
                dropped=dropped[0] and not outcome.succeeded, rotation=rotation,
                failure=None if outcome.failure is None else str(outcome.failure))


def summarize(name: str, runs: list[dict], wall_s: float) -> dict:
    for r in runs:
        r["kind"] = kind_of(r["success_step"] is not None, r["dropped"], r["rotation"])
    kinds = Counter(r["kind"] for r in runs)
    n = len(runs)
    steps = [r["success_step"] for r in runs if r["success_step"] is not None]
    res = dict(policy=name, episodes=n, **{k: kinds.get(k, 0) for k in KINDS},
               final_deg=float(np.mean([r["rotation"][-1] for r in runs])),
               max_deg=float(np.mean([max(r["rotation"]) for r in runs])),
               success_step=float(np.mean(steps)) if steps else float("nan"),
               steps_per_s=sum(len(r["rotation"]) for r in runs) / wall_s)
    print(f"{name:15s} success {res['success']:3d}/{n}  drop {res['drop']:3d}  short {res['short']:3d}  "
          f"lost {res['lost']:3d}  mean max {res['max_deg']:6.1f} deg, final {res['final_deg']:+6.1f} deg, "
          f"success at step {res['success_step']:5.1f}  ({res['steps_per_s']:.0f} steps/s)", flush=True)
    for r in runs:
        if r["kind"] != "success":
            trace = " ".join(f"{x:.0f}" for x in r["rotation"][::10])
            print(f"    seed {r['seed']}: {r['kind']:5s} max {max(r['rotation']):6.1f}, rotation every 10 steps: "
                  f"{trace}", flush=True)
    return res


def run_policy(name: str, task: str, seeds: range) -> tuple[dict, list[dict]]:
    t0 = time.perf_counter()
    if name == "executor":
        from gendex.solve.executor import StageExecutor

        env = gym.make(task, control_mode="pd_joint_pos", control_joint="both", **HISTORY_FREE)
        executor = StageExecutor()
        try:
            runs = [executor_episode(env, s, executor) for s in seeds]
        finally:
            env.close()
        return summarize(name, runs, time.perf_counter() - t0), runs
    env = gym.make(task, control_mode="pd_joint_delta_pos", control_joint="hand", **HISTORY_FREE)
    try:
        reset: Callable[[gym.Env, object], None] = lambda e, o: None  # noqa: E731
        if name == "random":
            rng = np.random.default_rng(0)
            act: Act = lambda e, o: rng.uniform(-1, 1, e.action_space.shape).astype(np.float32)  # noqa: E731
        elif name == "gait":
            gait = FingerGaitSolver()
            reset, act = gait.reset, gait.act
        else:
            version = env.unwrapped.task
            files = version.policy(STAGE)
            if files is None:
                raise SystemExit(f"{version.env_id} has no trained policy of stage {STAGE}")
            from gendex.solve.policy import StagePolicy  # loads SB3: only when there is a policy to run

            policy = StagePolicy.load(version, files)  # applies the saved obs normalization
            deterministic = name == "ppo"
            act = lambda e, o: policy.predict(o, deterministic=deterministic)  # noqa: E731
        runs = [stage_episode(env, s, reset, act) for s in seeds]
    finally:
        env.close()
    return summarize(name, runs, time.perf_counter() - t0), runs


def main(argv: list[str] | None = None) -> list[dict]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", default=TASK)
    ap.add_argument("--episodes", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0, help="first seed")
    ap.add_argument("--policies", nargs="+", choices=POLICIES, default=list(POLICIES))
    ap.add_argument("--traces", type=Path, help="write every attempt's rotation per step (degrees) here as JSON")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    seeds = range(args.seed, args.seed + args.episodes)
    print(f"{args.task}, seeds {seeds.start}-{seeds.stop - 1}")
    results, traces = [], {}
    for name in args.policies:
        res, runs = run_policy(name, args.task, seeds)
        results.append(res)
        traces[name] = runs
    if args.traces is not None:
        args.traces.write_text(json.dumps(dict(task=args.task, results=results, attempts=traces)))
    return results


if __name__ == "__main__":
    main()
