"""A picture of a skill at work: the stage executor solves a task, and the views at the first step the task
succeeds are saved side by side (docs/skills.md).

    .venv/bin/python scripts/skill_picture.py GenDex/PressButtonEstop-v0 docs/images/skills/press.png [--seed 0]
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

import numpy as np
from PIL import Image

import gendex_envs  # noqa: F401  (registers the GenDex/* ids)
from gendex.solve import SOLVER_ENV_KWARGS, SOLVERS
from gendex_envs.registry import make_task_env, resolve_task

log = logging.getLogger("skill_picture")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("task")
    ap.add_argument("out", type=Path)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--size", type=int, default=320)
    ap.add_argument("--views", nargs="+", default=["left_overhead", "right_overhead"])
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    env = make_task_env(resolve_task(args.task), render_mode="rgb_array", render_backend="cpu",
                        view_resolution=args.size, **SOLVER_ENV_KWARGS["stages"])
    solver = SOLVERS["stages"]()
    obs, info = env.reset(seed=args.seed)
    solver.reset(env, obs)
    try:
        while not bool(np.asarray(info.get("success", False)).reshape(-1)[0]):
            action = solver.act(env, obs)
            if action is None:
                raise SystemExit(f"{args.task}: the solver stopped on seed {args.seed} without success")
            obs, _, _, truncated, info = env.step(action)
            if bool(np.asarray(truncated).reshape(-1)[0]):
                raise SystemExit(f"{args.task}: the episode ended on seed {args.seed} without success")
        views = env.render_views(tuple(args.views))
        frame = np.concatenate([np.asarray(views[v][0]) for v in args.views], axis=1)
    finally:
        env.close()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(frame).save(args.out)
    log.info("wrote %s", args.out)


if __name__ == "__main__":
    main()
