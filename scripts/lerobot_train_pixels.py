"""lerobot's ACT or Diffusion Policy on a GenDex dataset from pixels plus joint state, through lerobot's own training
entry point (``lerobot.scripts.lerobot_train.train``).

Runs INSIDE the lerobot side venv (``bash scripts/lerobot_venv.sh`` builds ``.venv-lerobot``):

    .venv-lerobot/bin/python scripts/lerobot_train_pixels.py act \\
        out/datasets/gendex-lib-v2/PutAppleBowl-v1/lerobot --out out/lerobot/act-pixels --steps 200
    .venv-lerobot/bin/python scripts/lerobot_train_pixels.py diffusion \\
        out/datasets/gendex-lib-v2/PutAppleBowl-v1/lerobot --out out/lerobot/diffusion-pixels --steps 200

The only thing this file decides is the configuration lerobot's ``lerobot-train`` would otherwise read from its
command line: the policy's inputs are narrowed to ``observation.state`` and the dataset's camera(s)
(``observation.images.*``); the simulator's object poses (``observation.environment_state``), rewards and flags are
left out, which the command line cannot express. Everything else is lerobot's: its dataset and delta timestamps,
``make_policy``, ``make_pre_post_processors``, the policy's optimizer and scheduler presets, its training loop, its
checkpoints (``OUT/checkpoints/<step>/pretrained_model``). No backbone weights are fetched
(``pretrained_backbone_weights=None``; nothing may download here), so the ResNet-18 vision encoder starts from scratch.

Evaluate a checkpoint in the GenDex env with ``scripts/lerobot_act_policy.py OUT/checkpoints/last/pretrained_model``
(it serves any lerobot policy and renders the cameras the policy reads).

Besides lerobot's own output it writes ``OUT/loss.csv`` (step, loss, seconds a step for the update and for data, as
lerobot logs them every ``--log-every`` steps) and ``OUT/train_info.json`` (policy, inputs, steps, wall time,
mean seconds a step, final loss; also beside the weights); the last stdout line is that record as JSON.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import re
import sys
import time
from pathlib import Path
from typing import Any

os.environ.setdefault("HF_HUB_OFFLINE", "1")  # everything is local; never reach for the Hub
os.environ.setdefault("WANDB_MODE", "disabled")

log = logging.getLogger("lerobot_train_pixels")

REPO_ID = "local/gendex"
"""lerobot wants a repo id even for a local folder; nothing is fetched (HF_HUB_OFFLINE)."""
STATE = "observation.state"
IMAGE_PREFIX = "observation.images."
ACTION = "action"
_LOG_LINE = re.compile(r"step:(?P<step>\S+).*?loss:(?P<loss>[-0-9.e]+).*?updt_s:(?P<updt>[0-9.e-]+)"
                       r".*?data_s:(?P<data>[0-9.e-]+)")


class _LossLog(logging.Filter):
    """Collects lerobot's periodic training log lines ("step:200 ... loss:0.123 ... updt_s:... data_s:..."). A filter
    on the root logger, not a handler: lerobot's ``init_logging`` clears the root logger's handlers."""

    def __init__(self, every: int) -> None:
        super().__init__()
        self.every = every  # lerobot prints steps rounded (1K), so the step is counted from the lines instead
        self.rows: list[tuple[int, float, float, float]] = []

    def filter(self, record: logging.LogRecord) -> bool:
        m = _LOG_LINE.search(record.getMessage())
        if m:
            self.rows.append(((len(self.rows) + 1) * self.every, float(m["loss"]), float(m["updt"]), float(m["data"])))
        return True


def _dataset_record(root: Path) -> dict[str, Any]:
    """The task, ``gym.make`` keyword arguments and training seeds GenDex recorded in ``meta/gendex.json``."""
    meta = json.loads((root / "meta" / "gendex.json").read_text())
    return {"task_id": meta["task_id"], "env_kwargs": meta.get("env_kwargs", {}),
            "training_seeds": meta.get("episode_seeds", [])}


def _features(root: Path) -> tuple[dict[str, Any], dict[str, Any]]:
    from lerobot.configs.types import FeatureType
    from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata
    from lerobot.datasets.utils import dataset_to_policy_features

    meta = LeRobotDatasetMetadata(REPO_ID, root=root)
    features = dataset_to_policy_features(meta.features)
    cameras = sorted(k for k in features if k.startswith(IMAGE_PREFIX))
    if not cameras:
        raise ValueError(f"{root} records no camera ({IMAGE_PREFIX}*): its features are {sorted(features)}")
    if STATE not in features or ACTION not in features:
        raise ValueError(f"{root} lacks {STATE!r} or {ACTION!r}: its features are {sorted(features)}")
    if features[ACTION].type is not FeatureType.ACTION:
        raise ValueError(f"lerobot does not read {ACTION!r} as an action: {features[ACTION]}")
    inputs = {STATE: features[STATE], **{k: features[k] for k in cameras}}
    return inputs, {ACTION: features[ACTION]}


def _policy_config(kind: str, inputs: dict[str, Any], outputs: dict[str, Any], args: argparse.Namespace) -> Any:
    common = dict(input_features=inputs, output_features=outputs, device="cpu", push_to_hub=False,
                  pretrained_backbone_weights=None)
    if kind == "act":
        from lerobot.policies.act.configuration_act import ACTConfig

        return ACTConfig(**common, chunk_size=args.chunk, n_action_steps=args.chunk, dim_model=args.dim_model,
                         dim_feedforward=4 * args.dim_model, n_encoder_layers=args.layers, n_decoder_layers=1,
                         n_vae_encoder_layers=args.layers)
    from lerobot.policies.diffusion.configuration_diffusion import DiffusionConfig

    # 96 px frames: lerobot's default 84 px crop keeps most of the view; its UNet is kept, only narrower.
    return DiffusionConfig(**common, crop_shape=(84, 84), horizon=16, n_action_steps=8,
                           down_dims=(args.dim_model, 2 * args.dim_model), num_inference_steps=args.denoise_steps)


def train(args: argparse.Namespace) -> dict[str, Any]:
    from lerobot.configs.default import DatasetConfig
    from lerobot.configs.train import TrainPipelineConfig
    from lerobot.scripts.lerobot_train import train as lerobot_train

    root = Path(args.dataset).resolve()
    out = Path(args.out).resolve()
    if out.exists():
        raise FileExistsError(f"{out} exists: lerobot refuses to train into a used folder; pick another --out")
    inputs, outputs = _features(root)
    policy = _policy_config(args.policy, inputs, outputs, args)
    cfg = TrainPipelineConfig(
        dataset=DatasetConfig(repo_id=REPO_ID, root=str(root), use_imagenet_stats=False, video_backend="torchcodec"),
        policy=policy, output_dir=out, job_name=f"gendex-{args.policy}-pixels", seed=args.seed,
        num_workers=args.num_workers, batch_size=args.batch, steps=args.steps, log_freq=args.log_every,
        save_freq=args.steps, eval_freq=0)
    handler = _LossLog(args.log_every)
    logging.getLogger().addFilter(handler)
    t0 = time.perf_counter()
    lerobot_train(cfg)
    wall = time.perf_counter() - t0
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "loss.csv", "w") as f:
        f.write("step,loss,update_s,data_s\n")
        f.writelines(f"{s},{loss:.6f},{u:.4f},{d:.4f}\n" for s, loss, u, d in handler.rows)
    record = {
        "policy": args.policy, "dataset": str(root), "inputs": {k: list(f.shape) for k, f in inputs.items()},
        "steps": args.steps, "batch": args.batch, "seed": args.seed, "wall_s": round(wall, 1),
        "update_s_mean": round(sum(r[2] for r in handler.rows) / len(handler.rows), 3) if handler.rows else None,
        "data_s_mean": round(sum(r[3] for r in handler.rows) / len(handler.rows), 3) if handler.rows else None,
        "final_loss": handler.rows[-1][1] if handler.rows else None, "torch_threads": _threads(),
        "checkpoint": str(out / "checkpoints" / "last" / "pretrained_model"), **_dataset_record(root),
    }
    text = json.dumps(record, indent=1) + "\n"
    (out / "train_info.json").write_text(text)
    # beside the weights too: scripts/lerobot_act_policy.py reads the task, env kwargs and training seeds from there
    (Path(record["checkpoint"]) / "train_info.json").write_text(text)
    return record


def _threads() -> int:
    import torch

    return torch.get_num_threads()


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("policy", choices=("act", "diffusion"))
    p.add_argument("dataset", help="the LeRobot dataset folder (…/<Task>/lerobot) with a camera")
    p.add_argument("--out", required=True, help="lerobot's output folder (must not exist)")
    p.add_argument("--steps", type=int, default=200)
    p.add_argument("--batch", type=int, default=8, help="lerobot's default")
    p.add_argument("--chunk", type=int, default=20, help="ACT: actions predicted per step (20 = 1 s at 20 Hz)")
    p.add_argument("--dim-model", type=int, default=256, help="ACT: transformer width; Diffusion: first UNet width")
    p.add_argument("--layers", type=int, default=2, help="ACT: encoder and VAE encoder layers")
    p.add_argument("--denoise-steps", type=int, default=100, help="Diffusion: inference denoising steps")
    p.add_argument("--num-workers", type=int, default=1, help="dataloader processes (video decoding)")
    p.add_argument("--log-every", type=int, default=10)
    p.add_argument("--seed", type=int, default=1000)
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(message)s")
    record = train(args)
    sys.stdout.write(json.dumps(record) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
