"""Scene rebuilds with and without the frozen import-time heap (``gendex_envs.heap``).

A grasp choice rebuilds its trial scene for every candidate it tries in physics (``env.reset(options=
{"reconfigure": True})``), and ManiSkill ends each teardown with a full ``gc.collect()``. In one process this times,
alternating on each repeat: (a) a rebuild with the heap frozen, as GenDex runs (GenDex freezes before its first
scene; here the env built before the timing is frozen too, a few thousand objects more), and (b) the same after
``gc.unfreeze()``, as plain ManiSkill runs; then collecting start states (the scripted solver, grasp trials
included) both ways. Prints medians and the ratio (b) / (a).
"""

from __future__ import annotations

import argparse
import gc
import statistics
import time

import gymnasium as gym

import gendex_envs  # noqa: F401  (registers the GenDex tasks)
from gendex.train.start_states import collect_executor_states
from gendex_envs.registry import resolve_task


def timed(fn, frozen: bool) -> float:
    if frozen:
        gc.collect()
        gc.freeze()
    else:
        gc.unfreeze()
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--task", default="GenDex/PickUpBottle-v0")
    ap.add_argument("--rebuilds", type=int, default=10, help="timed rebuilds per repeat and side")
    ap.add_argument("--states", type=int, default=8, help="start states collected per repeat and side (0: skip)")
    ap.add_argument("--stage", default="lift_bottle", help="stage whose start states are collected")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()

    env = gym.make(args.task)
    env.reset(seed=0)
    tracked = {}

    def rebuilds():
        for k in range(args.rebuilds):
            env.reset(seed=k, options={"reconfigure": True})

    def states():
        collect_executor_states(resolve_task(args.task), args.stage, args.states, seed=0)

    work = {"scene rebuild": (rebuilds, args.rebuilds)}
    if args.states:
        work[f"start state ({args.stage})"] = (states, args.states)
    times = {(name, frozen): [] for name in work for frozen in (True, False)}
    for r in range(args.repeats):
        for name, (fn, n) in work.items():
            for frozen in (True, False):
                times[name, frozen].append(timed(fn, frozen) / n)
                tracked[frozen] = len(gc.get_objects())
        print(f"  repeat {r + 1}: " + "   ".join(f"{name} {'frozen' if f else 'unfrozen'} {t[-1]:.3f} s"
                                                 for (name, f), t in times.items()), flush=True)
    print(f"\nobjects a full collection walks: frozen heap {tracked[True]}, unfrozen {tracked[False]}")
    print(f"median of {args.repeats} repeats, seconds each")
    for name in work:
        a, b = statistics.median(times[name, True]), statistics.median(times[name, False])
        print(f"  {name:32s} frozen {a:7.3f}   unfrozen {b:7.3f}   ratio unfrozen / frozen {b / a:5.2f}")
    env.close()


if __name__ == "__main__":
    main()
