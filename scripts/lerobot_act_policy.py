"""A GenDex evaluation policy that is lerobot's ACT, served from the lerobot side venv (project venv side).

lerobot lives in ``.venv-lerobot`` and the GenDex env in ``.venv``; this module starts
``scripts/lerobot_act.py serve CHECKPOINT`` with the side venv's python and exchanges one JSON line per step with it
(the observation's ``observation.state`` and ``observation.environment_state`` out, the 26 absolute joint targets
back). Actions are clipped to the env's action space, as the BC baseline's are.

As a ``gendex eval`` policy (``module:factory``; the checkpoint comes from the environment):

    GENDEX_ACT_CHECKPOINT=out/act/apple-200 PYTHONPATH=scripts .venv/bin/gendex eval --suite gendex-ref-v1 \\
        --policy lerobot_act_policy:factory --tasks GenDex/PutAppleBowl-v1 --episodes 20 --out out/act/eval-ref

Or on the BC table's seeds (1 000 000 ..), through the same runner, with the task and env kwargs the checkpoint
recorded from its dataset:

    .venv/bin/python scripts/lerobot_act_policy.py out/act/apple-200 --episodes 50 --seed 1000000 \\
        --out out/act/eval-1000000.json

Environment: ``GENDEX_ACT_CHECKPOINT`` (required by ``factory``), ``GENDEX_LEROBOT_PYTHON`` (default
``.venv-lerobot/bin/python``), ``GENDEX_ACT_SERVE_ARGS`` (extra ``serve`` options, e.g.
``--temporal-ensemble 0.01`` or ``--n-action-steps 10``).
"""

from __future__ import annotations

import argparse
import atexit
import json
import logging
import os
import shlex
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np

log = logging.getLogger("lerobot_act_policy")

ROOT = Path(__file__).resolve().parents[1]
SERVER = ROOT / "scripts" / "lerobot_act.py"
STATE = "observation.state"
ENV_STATE = "observation.environment_state"
IMAGES = "observation.images."


class ServerError(RuntimeError):
    """The ACT server died or answered with an error."""


class LeRobotACTPolicy:
    """``reset()`` / ``act(obs)`` over a pipe to ``lerobot_act.py serve`` (see the module docstring)."""

    kind = "learned"

    def __init__(self, checkpoint: str | Path, python: str | Path | None = None,
                 serve_args: list[str] | None = None) -> None:
        self.checkpoint = Path(checkpoint)
        info = self.checkpoint / "train_info.json"
        self.info: dict[str, Any] = json.loads(info.read_text()) if info.is_file() else {}
        python = python or os.environ.get("GENDEX_LEROBOT_PYTHON") or ROOT / ".venv-lerobot" / "bin" / "python"
        cmd = [str(python), str(SERVER), "serve", str(self.checkpoint), *(serve_args or [])]
        env = {**os.environ, "OMP_NUM_THREADS": "1", "HF_HUB_OFFLINE": "1"}
        log.info("starting %s", shlex.join(cmd))
        self.proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env,
                                     bufsize=1)
        atexit.register(self.close)
        self.hello = self._read()
        self.inputs: dict[str, list[int]] = self.hello.get("inputs") or {STATE: [], ENV_STATE: []}
        self.cameras = sorted(k[len(IMAGES):] for k in self.inputs if k.startswith(IMAGES))
        self.low: np.ndarray | None = None
        self.high: np.ndarray | None = None

    @property
    def training_seeds(self) -> list[int]:
        return list(self.info.get("training_seeds", []))

    def _read(self) -> dict[str, Any]:
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        if not line:
            raise ServerError(f"the ACT server exited (code {self.proc.poll()}); its log is on stderr")
        msg = json.loads(line)
        if "error" in msg:
            raise ServerError(msg["error"])
        return msg

    def _ask(self, msg: dict[str, Any]) -> dict[str, Any]:
        assert self.proc.stdin is not None
        self.proc.stdin.write(json.dumps(msg) + "\n")
        self.proc.stdin.flush()
        return self._read()

    @property
    def observation_kwargs(self) -> dict[str, Any]:
        """A policy that reads camera frames asks the evaluation env to render its cameras at the trained size
        (channels-first shapes in lerobot's config: [3, H, W])."""
        if not self.cameras:
            return {}
        return {"obs_mode": "rgb", "sensor_resolution": self.inputs[IMAGES + self.cameras[0]][-1],
                "sensors": list(self.cameras)}

    def bind(self, env: Any) -> None:
        """Keep the env's action bounds (joint limits of the absolute targets): actions are clipped to them."""
        self.low, self.high = env.action_space.low, env.action_space.high

    def reset(self) -> None:
        self._ask({"cmd": "reset"})

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        payload = {k: (np.asarray(obs[k], dtype=np.uint8).tolist() if k.startswith(IMAGES)
                       else np.asarray(obs[k], dtype=np.float32).reshape(-1).tolist()) for k in self.inputs}
        action = np.asarray(self._ask({"cmd": "act", "obs": payload})["action"], dtype=np.float32)
        return np.clip(action, self.low, self.high) if self.low is not None else action

    def close(self) -> None:
        if self.proc.poll() is None:
            if self.proc.stdin is not None:
                self.proc.stdin.close()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()


def factory() -> LeRobotACTPolicy:
    """The ``gendex eval --policy lerobot_act_policy:factory`` entry (``GENDEX_ACT_CHECKPOINT`` names the folder)."""
    ckpt = os.environ.get("GENDEX_ACT_CHECKPOINT")
    if not ckpt:
        raise ValueError("set GENDEX_ACT_CHECKPOINT to a lerobot policy folder (scripts/lerobot_act.py train, or "
                         "OUT/checkpoints/last/pretrained_model of scripts/lerobot_train_pixels.py)")
    return LeRobotACTPolicy(ckpt, serve_args=shlex.split(os.environ.get("GENDEX_ACT_SERVE_ARGS", "")))


def evaluate(checkpoint: Path, episodes: int, seed: int, serve_args: list[str]) -> dict[str, Any]:
    """Run the checkpoint on its dataset's task for seeds ``seed ..`` with GenDex's evaluation runner."""
    from gendex.eval.metrics import wilson
    from gendex.eval.runner import evaluate_task

    policy = LeRobotACTPolicy(checkpoint, serve_args=serve_args)
    seeds = list(range(seed, seed + episodes))
    leaked = sorted(set(seeds) & set(policy.training_seeds))
    if leaked:
        raise ValueError(f"evaluation seeds {leaked[:5]} were training seeds of {checkpoint}")
    task = policy.info["task_id"]
    env_kwargs = {k: v for k, v in policy.info.get("env_kwargs", {}).items() if k != "reconfiguration_freq"}

    def show(r: Any) -> None:
        log.info("seed %d: %s in %d steps%s", r.seed, "success" if r.success_at_end else "fail", r.length,
                 f" ({r.failure})" if r.failure else "")

    try:
        results = evaluate_task(task, lambda: policy, seeds, env_kwargs=env_kwargs, progress=show)
    finally:
        policy.close()
    k = sum(r.success_at_end for r in results)
    lo, hi = wilson(k, len(results))
    return {"checkpoint": str(checkpoint), "task": task, "serve_args": serve_args, "episodes": len(results),
            "success_at_end": k, "success_once": sum(r.success_once for r in results), "rate": k / len(results),
            "wilson95": [lo, hi], "seeds": [seeds[0], seeds[-1]],
            "mean_length": sum(r.length for r in results) / len(results),
            "seconds": round(sum(r.seconds for r in results), 1),
            "per_episode": [r.to_dict() for r in results]}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Evaluate a lerobot ACT checkpoint in the GenDex env.")
    parser.add_argument("checkpoint", type=Path, help="a folder written by scripts/lerobot_act.py train")
    parser.add_argument("--episodes", type=int, default=20)
    parser.add_argument("--seed", type=int, default=1_000_000, help="first seed (datasets use 0 ..)")
    parser.add_argument("--serve-args", default="", help="extra options for lerobot_act.py serve")
    parser.add_argument("--out", type=Path, help="write the summary JSON here")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)s %(name)s: %(message)s",
                        datefmt="%H:%M:%S")
    summary = evaluate(args.checkpoint, args.episodes, args.seed, shlex.split(args.serve_args))
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(summary, indent=1) + "\n")
    print(json.dumps({k: v for k, v in summary.items() if k != "per_episode"}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
