"""The multi-task, language-conditioned policy from pixels: one camera and the robot's joint state, no simulator
object poses.

As :mod:`gendex.imitation.multitask`, but the environment state is replaced by a camera's frames: a small
convolutional encoder (stride-2 3x3 convolutions, GELU, then a linear layer) turns the frame into a vector, which is
concatenated with the normalized joint state, the step count and the instruction's MiniLM embedding and fed to the
same MLP head predicting an action chunk. Frames are shifted by up to :attr:`PixelConfig.shift` pixels while training
(random-shift augmentation, as DrQ and lerobot's diffusion policy crop), and frames are resized to
:attr:`PixelConfig.image_size` when loaded (area averaging), so a CPU can hold and learn from a library of them.

At run time the env must render that camera at that size: the policy's :attr:`PixelPolicy.observation_kwargs`
(``obs_mode="rgb"``, ``sensor_resolution``) are what the evaluation runner adds to ``gym.make``; they change what is
observed, not the physics. The checkpoint is a :mod:`gendex.imitation.bc` checkpoint of ``kind: "pixels"``.
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch
from torch import nn

from gendex.imitation import bc
from gendex.imitation.bc import _bad, _chunk_targets, _mlp
from gendex.imitation.frames import DatasetReadError, load_images
from gendex.imitation.multitask import (
    Embed,
    FrameSampler,
    PolicyTaskError,
    check_task_balance,
    embed_tasks,
    instruction_embedding,
    load_tasks,
)
from gendex_envs.observation import IMAGES, STATE

log = logging.getLogger(__name__)

KIND = "pixels"
MAX_IMAGE, MAX_CHANNELS, MAX_CONVS = 512, 1024, 8
"""Bounds of a pixel checkpoint's encoder config, checked before a network is built."""


@dataclass(frozen=True)
class PixelConfig:
    camera: str = "left_overhead"
    image_size: int = 64
    """Frames are resized to this square size when loaded."""
    channels: tuple[int, ...] = (32, 64, 64, 128)
    """Output channels of the stride-2 convolutions."""
    embed: int = 256
    """Size of the image's vector."""
    shift: int = 4
    """Random-shift augmentation in pixels (0: none)."""
    chunk: int = 10
    hidden: int = 1024
    layers: int = 3
    steps: int = 20_000
    batch: int = 128
    lr: float = 3e-4
    weight_decay: float = 1e-4
    obs_noise: float = 0.02
    ensemble_decay: float = 0.1
    task_balance: float = 0.0
    """As :attr:`gendex.imitation.multitask.MultiTaskConfig.task_balance`."""
    seed: int = 0

    def __post_init__(self):
        check_task_balance(self.task_balance)


class PixelNet(nn.Module):
    """Image [B, 3, S, S] uint8 and low-dimensional inputs [B, L] (normalized) -> [B, chunk * A]."""

    def __init__(self, n_low: int, n_out: int, image_size: int, channels: Sequence[int], embed: int, hidden: int,
                 layers: int):
        super().__init__()
        convs: list[nn.Module] = []
        c_in, side = 3, image_size
        for c in channels:
            convs += [nn.Conv2d(c_in, c, 3, stride=2, padding=1), nn.GELU()]
            c_in, side = c, (side + 1) // 2
        self.encoder = nn.Sequential(*convs, nn.Flatten(), nn.Linear(c_in * side * side, embed), nn.LayerNorm(embed))
        self.head = _mlp(embed + n_low, n_out, hidden, layers)

    def forward(self, image: torch.Tensor, low: torch.Tensor) -> torch.Tensor:
        z = self.encoder(image.float() / 255.0 - 0.5)
        return self.head(torch.cat([z, low], dim=1))


def _shift(images: torch.Tensor, pad: int, gen: torch.Generator) -> torch.Tensor:
    """Each image [N, C, H, W] shifted by up to ``pad`` pixels each way (edge-replicated, cropped back)."""
    if pad <= 0:
        return images
    n, c, h, w = images.shape
    padded = nn.functional.pad(images.float(), (pad, pad, pad, pad), mode="replicate")
    dx = torch.randint(0, 2 * pad + 1, (n,), generator=gen)
    dy = torch.randint(0, 2 * pad + 1, (n,), generator=gen)
    rows = (dy[:, None] + torch.arange(h)[None])[:, None, :, None]
    cols = (dx[:, None] + torch.arange(w)[None])[:, None, None, :]
    return padded[torch.arange(n)[:, None, None, None], torch.arange(c)[None, :, None, None], rows, cols]


def _low(state: np.ndarray, step: np.ndarray, emb: np.ndarray) -> np.ndarray:
    return np.concatenate([state, (step / bc.STEP_SCALE)[:, None], np.repeat(emb[None], len(state), 0)],
                          axis=1).astype(np.float32)


def train(datasets: Sequence[Path | str], out: Path | str, embed: Embed, demos: int | None = None,
          config: PixelConfig = PixelConfig(), progress: Callable[[int, float], None] | None = None) -> Path:
    """Train one pixel policy on every dataset (each with ``config.camera``'s video); writes ``<out>/bc.pt`` and
    ``<out>/bc.json`` (the loss every 1 000 steps) and returns the checkpoint's path."""
    tasks = load_tasks(datasets, demos)
    emb = embed_tasks(embed, tasks)
    images, lows, ys = [], [], []
    for path, t, e in zip(datasets, tasks, emb, strict=True):
        img = load_images(path, config.camera, demos, config.image_size)
        if len(img) != len(t.frames.action):
            raise DatasetReadError(f"{path}: {len(img)} frames of {config.camera} for {len(t.frames.action)} rows")
        images.append(np.ascontiguousarray(img.transpose(0, 3, 1, 2)))
        lows.append(_low(t.frames.state, t.frames.frame.astype(np.float32), e))
        ys.append(_chunk_targets(t.frames, config.chunk))
    image, low, y = np.concatenate(images), np.concatenate(lows), np.concatenate(ys)
    del images
    threads = torch.get_num_threads()
    try:
        model, ln, yn, curve, seconds = _fit(image, low, y, [len(v) for v in lows], config, progress)
    finally:
        torch.set_num_threads(threads)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    env_kwargs = {k: v for k, v in tasks[0].env_kwargs.items() if k not in ("obs_mode", "sensor_resolution", "sensors")}
    info = {"config": {**asdict(config), "channels": list(config.channels)},
            "names": {STATE: tasks[0].frames.names[STATE], "action": tasks[0].frames.names["action"]},
            "task_id": f"{KIND}:{len(tasks)}", "kind": KIND, "tasks": {t.task_id: t.instruction for t in tasks},
            "env_kwargs": env_kwargs, "training_seeds": sorted({s for t in tasks for s in t.seeds}),
            "demos": int(sum(t.frames.episodes for t in tasks)), "frames": len(low),
            "dataset": json.dumps([str(p) for p in datasets]), "final_loss": curve[-1][1] if curve else None,
            "seconds": seconds, "curve": [[int(s), float(v)] for s, v in curve]}
    norm = {"x_mean": ln.mean, "x_std": ln.std, "a_mean": yn.mean, "a_std": yn.std}
    path = bc.save_checkpoint(out / bc.CHECKPOINT, {**model.state_dict(), "_embeddings": torch.as_tensor(emb)},
                              norm, info)
    (out / "bc.json").write_text(json.dumps(info, indent=1) + "\n")
    log.info("trained a %d-task pixel policy on %d frames in %.0f s, loss %.4f -> %s", len(tasks), len(low), seconds,
             info["final_loss"] or 0.0, path)
    return path


def _fit(image: np.ndarray, low: np.ndarray, y: np.ndarray, counts: Sequence[int], config: PixelConfig, progress):
    torch.manual_seed(config.seed)
    gen = torch.Generator().manual_seed(config.seed)
    sample = FrameSampler(counts, config.task_balance, np.random.default_rng(config.seed))
    n, chunk, a = y.shape
    ln, yn = bc.Normalizer.fit(low), bc.Normalizer.fit(y.reshape(-1, a))
    it, lt = torch.from_numpy(image), torch.as_tensor(ln(low))
    yt = torch.as_tensor(yn(y).reshape(n, -1))
    model = PixelNet(low.shape[1], chunk * a, config.image_size, config.channels, config.embed, config.hidden,
                     config.layers)
    opt = torch.optim.AdamW(model.parameters(), lr=config.lr, weight_decay=config.weight_decay)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, config.steps)
    t0, loss_avg, curve = time.perf_counter(), None, []
    for step in range(config.steps):
        idx = torch.as_tensor(sample(min(config.batch, n)))
        img = _shift(it[idx], config.shift, gen)
        inp = lt[idx] + config.obs_noise * torch.randn(len(idx), lt.shape[1], generator=gen)
        loss = (model(img, inp) - yt[idx]).abs().mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
        sched.step()
        loss_avg = loss.item() if loss_avg is None else 0.98 * loss_avg + 0.02 * loss.item()
        if bc.curve_due(step + 1, config.steps):
            curve.append((step + 1, loss_avg))
            if progress is not None:
                progress(step + 1, loss_avg)
    return model, ln, yn, curve, round(time.perf_counter() - t0, 1)


class PixelPolicy(bc.BCPolicy):
    """A pixel checkpoint as an evaluation policy: it needs the env to render its camera
    (:attr:`observation_kwargs`), and takes the bound env's instruction as the multi-task policy does."""

    def __init__(self, path: Path | str, embed: Embed | None = None):
        self.embed = embed
        super().__init__(path)

    def __post_init__(self):
        ckpt = bc.load_checkpoint(self.path)
        emb = ckpt["model"].pop("_embeddings", None)
        cfg, tasks = ckpt["config"], ckpt.get("tasks")
        if ckpt.get("kind") != KIND or not isinstance(tasks, dict) or not all(
                isinstance(k, str) and isinstance(v, str) for k, v in tasks.items()):
            raise _bad(self.path, f"not a pixel checkpoint (kind {ckpt.get('kind')!r})")
        channels, size = cfg.get("channels"), cfg.get("image_size")
        if not (isinstance(channels, list) and 1 <= len(channels) <= MAX_CONVS
                and all(type(c) is int and 1 <= c <= MAX_CHANNELS for c in channels)
                and type(size) is int and 8 <= size <= MAX_IMAGE and type(cfg.get("embed")) is int
                and 1 <= cfg["embed"] <= bc.MAX_HIDDEN and isinstance(cfg.get("camera"), str)):
            raise _bad(self.path, f"its encoder config (channels {str(channels)[:80]}, image_size {size!r}, "
                                     f"embed, camera) is out of bounds: at most {MAX_CONVS} convolutions of "
                                     f"{MAX_CHANNELS} channels, images of 8 to {MAX_IMAGE} px")
        if emb is None or emb.ndim != 2 or len(emb) != len(tasks) or not bool(torch.isfinite(emb).all()):
            raise _bad(self.path, "_embeddings must be a finite [tasks, E] float tensor, a row per task")
        self.ckpt, self.chunk, self.decay = ckpt, cfg["chunk"], cfg["ensemble_decay"]
        self.instructions = dict(zip(tasks.values(), emb.numpy().astype(np.float32), strict=True))
        self.camera, self.size = cfg["camera"], size
        n_low, n_out = len(ckpt["x_mean"]), len(ckpt["a_mean"]) * self.chunk
        self.model = bc.build_network(lambda: PixelNet(n_low, n_out, size, channels, cfg["embed"], cfg["hidden"],
                                                       cfg["layers"]), ckpt["model"], self.path)
        self.x = bc.Normalizer(ckpt["x_mean"], ckpt["x_std"])
        self.a = bc.Normalizer(ckpt["a_mean"], ckpt["a_std"])

    @property
    def observation_kwargs(self) -> dict:
        """What the env must render for this policy (added to ``gym.make`` by the evaluation runner)."""
        return {"obs_mode": "rgb", "sensor_resolution": self.size, "sensors": [self.camera]}

    def bind(self, env) -> None:
        self.emb = instruction_embedding(self, env)
        self.low, self.high = env.action_space.low, env.action_space.high

    @torch.no_grad()
    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        key = IMAGES + self.camera
        if key not in obs:
            raise PolicyTaskError(f"the observation has no {key}: make the env with {self.observation_kwargs}")
        image = np.asarray(obs[key], np.uint8)
        if image.shape[:2] != (self.size, self.size):
            from PIL import Image

            image = np.asarray(Image.fromarray(image).resize((self.size, self.size), Image.BOX))
        low = _low(obs[STATE][None], np.array([self.t], np.float32), self.emb)
        pred = self.model(torch.from_numpy(image.transpose(2, 0, 1).copy())[None],
                          torch.as_tensor(self.x(low))).numpy().reshape(self.chunk, -1)
        return self._ensemble(pred)


__all__ = ["KIND", "PixelConfig", "PixelNet", "PixelPolicy", "train"]
