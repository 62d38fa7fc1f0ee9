"""lerobot's own ACT policy on a GenDex dataset: train it, then serve it to the GenDex env over a pipe.

Runs INSIDE the lerobot side venv (``bash scripts/lerobot_venv.sh`` builds ``.venv-lerobot``), never the project's:
lerobot 0.4.4 and the project's torch cannot share a venv. The GenDex env lives only in the project venv, so
evaluation goes through ``scripts/lerobot_act_policy.py`` (project venv), which starts ``serve`` here as a subprocess.

    # train on state + environment state (no images), CPU, one thread
    .venv-lerobot/bin/python scripts/lerobot_act.py train \\
        out/datasets/gendex-putapplebowl-v1/PutAppleBowl-v1/lerobot --out out/act/apple-200 \\
        --steps 5000 --batch 64 --chunk 20 --vae-layers 1
    # answer observation JSON lines on stdin with action JSON lines on stdout (what lerobot_act_policy.py drives)
    .venv-lerobot/bin/python scripts/lerobot_act.py serve out/act/apple-200

Training follows lerobot's own ``lerobot_train.py``: the policy comes from ``make_policy`` with the dataset's metadata,
the normalization from ``make_pre_post_processors`` with the dataset's stats (MEAN_STD on state, environment state and
action), the action chunks from ``LeRobotDataset`` with the config's delta timestamps (``action_is_pad`` past an
episode's end), and the optimizer from the config's preset (AdamW, gradient clipping at its ``grad_clip_norm``). Only
the input features are narrowed to ``observation.state`` and ``observation.environment_state`` (by default lerobot
takes every non-action feature, rewards and flags included), and the model is smaller than lerobot's Aloha default,
so that a CPU core trains it in minutes. The dataset is read once into tensors (its frames as lerobot returns them),
because one core cannot afford lerobot's per-item decoding at every step.

``train`` writes into ``--out``: the policy (``save_pretrained``: ``config.json``, ``model.safetensors``), the pre- and
post-processors (with the normalization stats), ``loss.csv`` (the loss curve) and ``train_info.json`` (dataset, task,
``gym.make`` keyword arguments and training seeds from the dataset's ``meta/gendex.json``, steps, time, final loss);
its last stdout line is that record as JSON. ``serve`` loads any lerobot policy checkpoint (this script's, or one
``scripts/lerobot_train_pixels.py`` trained with lerobot's own entry point: ACT or Diffusion from camera frames) and
speaks one JSON object per line: it greets first with ``{"ready": true, "type": ..., "inputs": {feature: shape}, ...}``;
``{"cmd": "reset"}`` -> ``{"ok": true}``; ``{"cmd": "act", "obs": {...}}`` with one entry per input feature
(vectors as lists; ``observation.images.*`` as H x W x 3 uint8 nested lists) -> ``{"action": [...]}``; errors come
back as ``{"error": "..."}``.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import sys
import time
from pathlib import Path
from typing import Any, TextIO

os.environ.setdefault("HF_HUB_OFFLINE", "1")  # everything is local; never reach for the Hub
os.environ.setdefault("OMP_NUM_THREADS", "1")

import torch  # (after the environment variables above)

log = logging.getLogger("lerobot_act")

STATE = "observation.state"
ENV_STATE = "observation.environment_state"
ACTION = "action"
IMAGE_PREFIX = "observation.images."
INPUTS = (STATE, ENV_STATE)
REPO_ID = "local/gendex"
"""lerobot wants a repo id even for a local folder; nothing is fetched (HF_HUB_OFFLINE)."""


def _act_config(meta: Any, args: argparse.Namespace) -> Any:
    from lerobot.configs.types import FeatureType
    from lerobot.datasets.utils import dataset_to_policy_features
    from lerobot.policies.act.configuration_act import ACTConfig

    features = dataset_to_policy_features(meta.features)
    missing = [k for k in (*INPUTS, ACTION) if k not in features]
    if missing:
        raise ValueError(f"the dataset lacks {missing}: its features are {sorted(features)}")
    if features[ACTION].type is not FeatureType.ACTION:
        raise ValueError(f"lerobot does not read {ACTION!r} as an action: {features[ACTION]}")
    return ACTConfig(
        input_features={k: features[k] for k in INPUTS},
        output_features={ACTION: features[ACTION]},
        device="cpu",
        push_to_hub=False,
        chunk_size=args.chunk,
        n_action_steps=args.chunk,
        dim_model=args.dim_model,
        n_heads=args.heads,
        dim_feedforward=args.dim_feedforward,
        n_encoder_layers=args.encoder_layers,
        n_decoder_layers=1,
        n_vae_encoder_layers=args.vae_layers,
        use_vae=not args.no_vae,
        kl_weight=args.kl_weight,
        dropout=args.dropout,
        optimizer_lr=args.lr,
        optimizer_weight_decay=args.weight_decay,
    )


def _load_tensors(dataset: Any) -> dict[str, torch.Tensor]:
    """Every frame of ``dataset`` as lerobot's ``__getitem__`` returns it (inputs, action chunk, padding mask),
    stacked into tensors."""
    keys = (*INPUTS, ACTION, "action_is_pad")
    rows: dict[str, list[torch.Tensor]] = {k: [] for k in keys}
    t0 = time.perf_counter()
    for i in range(len(dataset)):
        item = dataset[i]
        for k in keys:
            rows[k].append(item[k])
        if (i + 1) % 5000 == 0:
            log.info("read %d/%d frames (%.0f s)", i + 1, len(dataset), time.perf_counter() - t0)
    return {k: torch.stack(v) for k, v in rows.items()}


def _dataset_record(root: Path) -> dict[str, Any]:
    path = root / "meta" / "gendex.json"
    if not path.is_file():
        log.warning("%s is missing: no task id, env kwargs or training seeds recorded", path)
        return {}
    meta = json.loads(path.read_text())
    return {"task_id": meta.get("task_id"), "env_kwargs": meta.get("env_kwargs", {}),
            "training_seeds": meta.get("episode_seeds", [])}


def train(args: argparse.Namespace) -> dict[str, Any]:
    from lerobot.datasets.factory import resolve_delta_timestamps
    from lerobot.datasets.lerobot_dataset import LeRobotDataset, LeRobotDatasetMetadata
    from lerobot.policies.factory import make_policy, make_pre_post_processors

    torch.set_num_threads(args.threads)
    torch.manual_seed(args.seed)
    root = Path(args.dataset).resolve()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    meta = LeRobotDatasetMetadata(REPO_ID, root=root)
    cfg = _act_config(meta, args)
    policy = make_policy(cfg, ds_meta=meta)
    preprocessor, postprocessor = make_pre_post_processors(cfg, dataset_stats=meta.stats)
    n_params = sum(p.numel() for p in policy.parameters())
    log.info("ACT: %d parameters, chunk %d, inputs %s", n_params, cfg.chunk_size,
             {k: list(f.shape) for k, f in cfg.input_features.items()})

    dataset = LeRobotDataset(REPO_ID, root=root, delta_timestamps=resolve_delta_timestamps(cfg, meta))
    log.info("dataset %s: %d episodes, %d frames at %d fps", root, dataset.num_episodes, len(dataset), dataset.fps)
    data = _load_tensors(dataset)
    n = len(data[ACTION])

    optim_cfg = cfg.get_optimizer_preset()
    optimizer = optim_cfg.build(policy.get_optim_params())
    gen = torch.Generator().manual_seed(args.seed)
    curve = (out / "loss.csv").open("w")
    curve.write("step,loss,l1_loss,kld_loss,grad_norm,seconds\n")
    policy.train()
    t0 = time.perf_counter()
    sums = {"loss": 0.0, "l1_loss": 0.0, "kld_loss": 0.0, "grad_norm": 0.0}
    window = 0
    last: dict[str, float] = {}
    for step in range(1, args.steps + 1):
        idx = torch.randint(0, n, (args.batch,), generator=gen)
        batch = preprocessor({k: v[idx] for k, v in data.items()})
        loss, parts = policy.forward(batch)
        optimizer.zero_grad(set_to_none=True)
        loss.backward()
        grad_norm = torch.nn.utils.clip_grad_norm_(policy.parameters(), optim_cfg.grad_clip_norm)
        optimizer.step()
        sums["loss"] += loss.item()
        sums["l1_loss"] += parts.get("l1_loss", math.nan)
        sums["kld_loss"] += parts.get("kld_loss", 0.0)
        sums["grad_norm"] += float(grad_norm)
        window += 1
        if step % args.log_every == 0 or step == args.steps:
            last = {k: v / window for k, v in sums.items()}
            elapsed = time.perf_counter() - t0
            curve.write(f"{step},{last['loss']:.6f},{last['l1_loss']:.6f},{last['kld_loss']:.6f},"
                        f"{last['grad_norm']:.4f},{elapsed:.1f}\n")
            curve.flush()
            log.info("step %d/%d: loss %.4f (l1 %.4f, kld %.4f), grad %.2f, %.3f s/step", step, args.steps,
                     last["loss"], last["l1_loss"], last["kld_loss"], last["grad_norm"], elapsed / step)
            sums = dict.fromkeys(sums, 0.0)
            window = 0
    seconds = time.perf_counter() - t0
    curve.close()

    policy.save_pretrained(out)
    preprocessor.save_pretrained(out)
    postprocessor.save_pretrained(out)
    record = {"dataset": str(root), "episodes": dataset.num_episodes, "frames": n, "steps": args.steps,
              "batch": args.batch, "chunk_size": cfg.chunk_size, "lr": args.lr, "parameters": n_params,
              "train_seconds": round(seconds, 1), "seconds_per_step": round(seconds / args.steps, 4),
              "final_loss": last.get("loss"), "final_l1_loss": last.get("l1_loss"),
              "final_kld_loss": last.get("kld_loss"), "lerobot_config": {
                  "dim_model": cfg.dim_model, "n_heads": cfg.n_heads, "dim_feedforward": cfg.dim_feedforward,
                  "n_encoder_layers": cfg.n_encoder_layers, "n_vae_encoder_layers": cfg.n_vae_encoder_layers,
                  "use_vae": cfg.use_vae, "kl_weight": cfg.kl_weight, "dropout": cfg.dropout},
              **_dataset_record(root)}
    (out / "train_info.json").write_text(json.dumps(record, indent=1) + "\n")
    log.info("saved the policy and its processors in %s (%.0f s of training)", out, seconds)
    return record


def load(checkpoint: Path, temporal_ensemble: float | None, n_action_steps: int | None) -> tuple[Any, Any, Any]:
    """The saved lerobot policy (ACT from ``train`` here, or ACT or Diffusion from ``lerobot_train_pixels.py``) with
    its pre- and post-processors. ACT's inference may switch to temporal ensembling (a prediction every step,
    ``n_action_steps`` 1); any policy may execute ``n_action_steps`` actions of each predicted chunk."""
    from lerobot.configs.policies import PreTrainedConfig
    from lerobot.policies.factory import get_policy_class, make_pre_post_processors

    cfg = PreTrainedConfig.from_pretrained(checkpoint)
    if temporal_ensemble is not None:
        if not hasattr(cfg, "temporal_ensemble_coeff"):
            raise ValueError(f"--temporal-ensemble is ACT's; {checkpoint} holds a {cfg.type} policy")
        cfg.temporal_ensemble_coeff = temporal_ensemble
        cfg.n_action_steps = 1
    elif n_action_steps is not None:
        cfg.n_action_steps = n_action_steps
    cfg.device = "cpu"
    policy = get_policy_class(cfg.type).from_pretrained(checkpoint, config=cfg)
    policy.eval()
    pre, post = make_pre_post_processors(cfg, pretrained_path=str(checkpoint))
    return policy, pre, post


def _observation(msg_obs: dict[str, Any], keys: list[str]) -> dict[str, torch.Tensor]:
    """The policy's inputs from one JSON observation: vectors as float32; camera frames (``observation.images.*``,
    H x W x 3 uint8 as the env renders them) as float32 3 x H x W in [0, 1], as ``LeRobotDataset`` returns frames."""
    missing = [k for k in keys if k not in msg_obs]
    if missing:
        raise KeyError(f"the observation lacks {missing}; the policy reads {keys}")
    obs = {}
    for k in keys:
        if k.startswith(IMAGE_PREFIX):
            obs[k] = torch.tensor(msg_obs[k], dtype=torch.uint8).permute(2, 0, 1).float() / 255.0
        else:
            obs[k] = torch.tensor(msg_obs[k], dtype=torch.float32)
    return obs


def serve(args: argparse.Namespace) -> None:
    torch.set_num_threads(args.threads)
    out: TextIO = sys.stdout
    sys.stdout = sys.stderr  # only replies go to the pipe, whatever a library prints
    policy, pre, post = load(Path(args.checkpoint), args.temporal_ensemble, args.n_action_steps)
    cfg = policy.config
    inputs = sorted(cfg.input_features)
    chunk = getattr(cfg, "chunk_size", None) or getattr(cfg, "horizon", None)
    ensemble = getattr(cfg, "temporal_ensemble_coeff", None)
    log.info("serving %s %s (inputs %s, chunk %s, n_action_steps %d, temporal ensembling %s)", cfg.type,
             args.checkpoint, inputs, chunk, cfg.n_action_steps, ensemble)

    def reply(obj: dict[str, Any]) -> None:
        out.write(json.dumps(obj) + "\n")
        out.flush()

    reply({"ready": True, "type": cfg.type, "inputs": {k: list(cfg.input_features[k].shape) for k in inputs},
           "chunk_size": chunk, "n_action_steps": cfg.n_action_steps, "temporal_ensemble_coeff": ensemble})
    for line in sys.stdin:
        if not line.strip():
            continue
        try:
            msg = json.loads(line)
            if msg.get("cmd") == "reset":
                policy.reset()
                reply({"ok": True})
            elif msg.get("cmd") == "act":
                obs = _observation(msg["obs"], inputs)
                with torch.inference_mode():
                    action = post(policy.select_action(pre(obs)))
                reply({"action": action.reshape(-1).tolist()})
            else:
                reply({"error": f"unknown message {msg!r}"})
        except Exception as exc:  # report to the driver, keep serving
            log.exception("request failed")
            reply({"error": f"{type(exc).__name__}: {exc}"})


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    t = sub.add_parser("train", help="train ACT on a GenDex LeRobot dataset (state + environment state)")
    t.add_argument("dataset", help="the LeRobot dataset folder (…/<Task>/lerobot)")
    t.add_argument("--out", required=True, help="folder for the policy, processors and loss curve")
    t.add_argument("--steps", type=int, default=5000)
    t.add_argument("--batch", type=int, default=64)
    t.add_argument("--chunk", type=int, default=20, help="actions predicted per step (20 = 1 s at 20 Hz)")
    t.add_argument("--lr", type=float, default=1e-4)
    t.add_argument("--weight-decay", type=float, default=1e-4)
    t.add_argument("--dim-model", type=int, default=256)
    t.add_argument("--heads", type=int, default=8)
    t.add_argument("--dim-feedforward", type=int, default=1024)
    t.add_argument("--encoder-layers", type=int, default=4, help="layers of the transformer encoder")
    t.add_argument("--vae-layers", type=int, default=1, help="layers of the VAE encoder (it reads the whole chunk)")
    t.add_argument("--no-vae", action="store_true", help="drop ACT's variational objective")
    t.add_argument("--kl-weight", type=float, default=10.0)
    t.add_argument("--dropout", type=float, default=0.1)
    t.add_argument("--log-every", type=int, default=100)
    t.add_argument("--seed", type=int, default=0)
    t.add_argument("--threads", type=int, default=1)
    s = sub.add_parser("serve", help="answer observation JSON lines on stdin with action JSON lines")
    s.add_argument("checkpoint", help="a folder written by train")
    s.add_argument("--temporal-ensemble", type=float, default=None,
                   help="ACT's temporal ensembling coefficient (predict every step); default: run chunks")
    s.add_argument("--n-action-steps", type=int, default=None, help="actions executed per chunk (default: saved)")
    s.add_argument("--threads", type=int, default=1)
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, stream=sys.stderr,
                        format="%(asctime)s %(levelname)s %(name)s: %(message)s", datefmt="%H:%M:%S")
    if args.command == "train":
        record = train(args)
        print(json.dumps({k: v for k, v in record.items() if k != "training_seeds"}), flush=True)
    else:
        serve(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
