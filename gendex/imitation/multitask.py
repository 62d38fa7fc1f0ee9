"""One behaviour-cloning policy for many tasks, told which by its instruction: the multi-task, language-conditioned
baseline of the library datasets.

It learns from several GenDex datasets at once (one task each, as ``gendex dataset build`` lays them out) and sees,
per frame, what the single-task baseline (:mod:`gendex.imitation.bc`) sees: ``observation.state`` (by default its
joint positions only, not the velocities: :attr:`MultiTaskConfig.joint_velocity`),
``observation.environment_state`` and the step count; and the task's instruction, embedded once per task by a
sentence encoder (all-MiniLM-L6-v2, the model the generator measures instruction diversity with; the caller passes
the ``embed`` function, so this module needs no language model of its own). The environment states of different
tasks differ in length (each lists its own objects); they are zero-padded to the longest (``world_dim``). The network
is :func:`gendex.imitation.bc._mlp` on the concatenated, normalized inputs, predicting an action chunk, trained with
an L1 loss, executed with temporal ensembling, as the single-task baseline.

Every dataset must share the robot's state and action names and ``gym.make`` keyword arguments: one policy, one
action space. The checkpoint is a :mod:`gendex.imitation.bc` checkpoint (tensors and JSON values only, loaded with
``weights_only``) with ``kind: "multitask"``, the tasks it learned with their instructions, and the instructions'
embeddings; at run time the policy takes the instruction of the env it is bound to (``env.unwrapped.task_spec``) and
uses its embedding, embedding it with ``embed`` when it is not one it learned.
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

from gendex.imitation.bc import (
    CHECKPOINT,
    MAX_FEATURES,
    BCPolicy,
    Normalizer,
    PolicyTaskError,
    _bad,
    _chunk_targets,
    _dataset_meta,
    _mlp,
    build_network,
    curve_due,
    load_checkpoint,
    save_checkpoint,
)
from gendex.imitation.frames import DatasetReadError, Frames, load_frames
from gendex_envs.observation import ENVIRONMENT_STATE, STATE, VELOCITY_SUFFIX

log = logging.getLogger(__name__)

KIND = "multitask"
Embed = Callable[[list[str]], np.ndarray]
"""Texts -> [N, E] float embeddings (unit length: all-MiniLM-L6-v2's ``normalize_embeddings``)."""


@dataclass(frozen=True)
class MultiTaskConfig:
    chunk: int = 10
    """Actions predicted per step."""
    hidden: int = 1024
    layers: int = 4
    steps: int = 40_000
    """Gradient steps."""
    batch: int = 512
    lr: float = 5e-4
    weight_decay: float = 1e-4
    obs_noise: float = 0.02
    """Std of the Gaussian noise added to normalized inputs while training."""
    ensemble_decay: float = 0.1
    """Temporal ensembling: the weight of a prediction made k steps ago is exp(-decay * k)."""
    task_balance: float = 0.0
    """How a batch shares out over tasks: 0 draws frames uniformly (a task's share is its share of the frames, so
    long demonstrations dominate), 1 draws each task equally often; in between a task's share is frames^(1 - b)."""
    joint_velocity: bool = False
    """Whether the network reads the joint velocities of ``observation.state`` (its ``.vel`` entries) besides the
    positions. Off by default: with them the fit leans on the velocity (the next target is nearly the position plus
    the velocity's step) and the policy drifts in closed loop; without them single-task press went from 0/10 to 9/10
    on held-out seeds (benchmarks/results/imitation.md). Checkpoints written before this field read them."""
    seed: int = 0

    def __post_init__(self):
        check_task_balance(self.task_balance)
        if type(self.joint_velocity) is not bool:
            raise ValueError(f"joint_velocity {self.joint_velocity!r} must be True or False")



def state_columns(names: Sequence[str], joint_velocity: bool) -> np.ndarray:
    """Indices of the ``observation.state`` entries (named ``names``) the network reads: all of them, or with
    ``joint_velocity`` False all but the velocities."""
    return np.array([i for i, n in enumerate(names) if joint_velocity or not n.endswith(VELOCITY_SUFFIX)], np.int64)


def check_task_balance(value: float) -> None:
    """ValueError unless ``value`` is a task balance (:attr:`MultiTaskConfig.task_balance`): from 0 to 1."""
    if not 0.0 <= value <= 1.0:
        raise ValueError(f"task_balance {value!r} must be from 0 (frames uniform) to 1 (tasks equal)")


class FrameSampler:
    """Draws training rows from tasks laid end to end (``counts`` rows each), a task's share of the draws being
    ``counts ** (1 - balance)`` normalised, uniform within a task."""

    def __init__(self, counts: Sequence[int], balance: float, rng: np.random.Generator):
        counts = np.asarray(counts, np.float64)
        if counts.ndim != 1 or not len(counts) or (counts < 1).any():
            raise ValueError(f"every task needs at least one frame; counts {counts.tolist()[:10]}")
        share = counts ** (1.0 - balance)
        per_row = np.repeat(share / share.sum() / counts, counts.astype(np.int64))
        self.cdf = np.cumsum(per_row)
        self.cdf /= self.cdf[-1]
        self.rng = rng

    def __call__(self, size: int) -> np.ndarray:
        return np.minimum(np.searchsorted(self.cdf, self.rng.random(size), side="right"), len(self.cdf) - 1)


@dataclass(frozen=True)
class TaskData:
    task_id: str
    instruction: str
    frames: Frames
    seeds: list[int]
    env_kwargs: dict


def _instruction(root: Path) -> str:
    """The dataset's one instruction (``meta/tasks.parquet``: a task version has one)."""
    import pyarrow.parquet as pq

    from gendex.imitation.frames import lerobot_root

    tasks = pq.read_table(lerobot_root(root) / "meta" / "tasks.parquet").column("task").to_pylist()
    if len(tasks) != 1:
        raise DatasetReadError(f"{root}: a multi-task policy needs one instruction per dataset; found {len(tasks)}")
    return str(tasks[0])


def load_tasks(datasets: Sequence[Path | str], demos: int | None = None) -> list[TaskData]:
    """Each dataset's frames, task, instruction and training seeds; :class:`DatasetReadError` when two datasets
    are of one task, or their robots' state or action names or ``gym.make`` arguments differ."""
    out: list[TaskData] = []
    for path in datasets:
        root = Path(path)
        frames = load_frames(root, demos)
        meta = _dataset_meta(root)
        out.append(TaskData(meta["task_id"], _instruction(root), frames,
                            [int(s) for s in meta.get("episode_seeds", [])[:frames.episodes]], meta["env_kwargs"]))
    if not out:
        raise DatasetReadError("a multi-task policy needs at least one dataset")
    first = out[0]
    for t in out[1:]:
        for key in (STATE, "action"):
            if t.frames.names[key] != first.frames.names[key]:
                raise DatasetReadError(f"{t.task_id} and {first.task_id} differ in {key} names: one policy acts "
                                       "for one robot")
        if t.env_kwargs != first.env_kwargs:
            raise DatasetReadError(f"{t.task_id} was collected with {t.env_kwargs}, {first.task_id} with "
                                   f"{first.env_kwargs}: one policy has one action space")
    ids = [t.task_id for t in out]
    if len(set(ids)) != len(ids):
        raise DatasetReadError(f"a task is given twice: {sorted(i for i in ids if ids.count(i) > 1)}")
    return out


def embed_tasks(embed: Embed, tasks: Sequence[TaskData]) -> np.ndarray:
    """[T, E] the embeddings of the tasks' instructions; ValueError unless one finite row per task."""
    emb = np.asarray(embed([t.instruction for t in tasks]), np.float32)
    if emb.ndim != 2 or len(emb) != len(tasks) or not np.isfinite(emb).all():
        raise ValueError(f"embed gave an array of shape {emb.shape}; one finite row per instruction is needed")
    return emb


def instruction_embedding(policy, env) -> np.ndarray:
    """The embedding a multi-task ``policy`` acts on in ``env``: its learned row for the env's instruction, or
    ``policy.embed``'s for one it did not learn (:class:`PolicyTaskError` without an encoder)."""
    text = env.unwrapped.task_spec.instruction
    if text in policy.instructions:
        return policy.instructions[text]
    if policy.embed is None:
        raise PolicyTaskError(f"multi-task policy {policy.path} did not learn {text!r} and has no embed function "
                              f"for a new instruction; it learned {len(policy.instructions)} instructions")
    log.info("multi-task policy %s: %r is not an instruction it learned; acting on its embedding", policy.path, text)
    return np.asarray(policy.embed([text]), np.float32)[0]


def _inputs(state: np.ndarray, world: np.ndarray, step: np.ndarray, emb: np.ndarray, world_dim: int) -> np.ndarray:
    """[N, S + world_dim + 1 + E]: state, the environment state zero-padded to ``world_dim``, step / 200, and the
    instruction's embedding (one row, repeated)."""
    from gendex.imitation.bc import STEP_SCALE

    n = len(state)
    pad = np.zeros((n, world_dim), np.float32)
    pad[:, :world.shape[1]] = world
    return np.concatenate([state, pad, (step / STEP_SCALE)[:, None], np.repeat(emb[None], n, 0)],
                          axis=1).astype(np.float32)


def train(datasets: Sequence[Path | str], out: Path | str, embed: Embed, demos: int | None = None,
          config: MultiTaskConfig = MultiTaskConfig(),
          progress: Callable[[int, float], None] | None = None, threads: int = 1) -> Path:
    """Train one policy on every dataset (the first ``demos`` episodes of each); writes ``<out>/bc.pt`` and
    ``<out>/bc.json`` (with the loss every 1 000 steps: the learning curve) and returns the checkpoint's path.

    ``threads``: torch threads for the fit. One by default (two cores shared with other work: more only contend);
    on an idle machine more are faster (0.078 against 0.142 s a step with two, the library's default network)."""
    if threads < 1:
        raise ValueError(f"threads {threads!r} must be at least 1")
    tasks = load_tasks(datasets, demos)
    emb = embed_tasks(embed, tasks)
    world_dim = max(t.frames.environment_state.shape[1] for t in tasks)
    keep = state_columns(tasks[0].frames.names[STATE], config.joint_velocity)
    xs, ys = [], []
    for t, e in zip(tasks, emb, strict=True):
        f = t.frames
        xs.append(_inputs(f.state[:, keep], f.environment_state, f.frame.astype(np.float32), e, world_dim))
        ys.append(_chunk_targets(f, config.chunk))
    x, y = np.concatenate(xs), np.concatenate(ys)
    if x.shape[1] > MAX_FEATURES:
        raise ValueError(f"{x.shape[1]} input features; a checkpoint holds at most {MAX_FEATURES}")
    before = torch.get_num_threads()
    torch.set_num_threads(threads)
    try:
        model, xn, yn, curve, seconds = _fit(x, y, [len(c) for c in xs], config, progress)
    finally:
        torch.set_num_threads(before)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    first = tasks[0]
    names = {STATE: first.frames.names[STATE], "action": first.frames.names["action"],
             ENVIRONMENT_STATE: [f"world.{i}" for i in range(world_dim)]}
    info = {"config": asdict(config), "names": names, "task_id": f"{KIND}:{len(tasks)}", "kind": KIND,
            "tasks": {t.task_id: t.instruction for t in tasks}, "world_dim": world_dim,
            "env_kwargs": first.env_kwargs,
            "training_seeds": sorted({s for t in tasks for s in t.seeds}),
            "demos": int(sum(t.frames.episodes for t in tasks)), "frames": len(x),
            "dataset": json.dumps([str(p) for p in datasets]), "final_loss": curve[-1][1] if curve else None,
            "seconds": seconds, "threads": threads, "curve": [[int(s), float(v)] for s, v in curve]}
    norm = {"x_mean": xn.mean, "x_std": xn.std, "a_mean": yn.mean, "a_std": yn.std}
    path = save_checkpoint(out / CHECKPOINT, {**model.state_dict(), "_embeddings": torch.as_tensor(emb)}, norm, info)
    (out / "bc.json").write_text(json.dumps(info, indent=1) + "\n")
    log.info("trained a %d-task policy on %d demos (%d frames) in %.0f s, loss %.4f -> %s", len(tasks),
             info["demos"], len(x), seconds, info["final_loss"] or 0.0, path)
    return path


def _fit(x: np.ndarray, y: np.ndarray, counts: Sequence[int], config: MultiTaskConfig, progress):
    torch.manual_seed(config.seed)
    sample = FrameSampler(counts, config.task_balance, np.random.default_rng(config.seed))
    n, chunk, a = y.shape
    xn, yn = Normalizer.fit(x), Normalizer.fit(y.reshape(-1, a))
    xt = torch.as_tensor(xn(x))
    yt = torch.as_tensor(yn(y).reshape(n, -1))
    model = _mlp(x.shape[1], chunk * a, config.hidden, config.layers)
    opt = torch.optim.AdamW(model.parameters(), lr=config.lr, weight_decay=config.weight_decay)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, config.steps)
    t0, loss_avg, curve = time.perf_counter(), None, []
    for step in range(config.steps):
        idx = torch.as_tensor(sample(min(config.batch, n)))
        loss = (model(xt[idx] + config.obs_noise * torch.randn(len(idx), xt.shape[1])) - yt[idx]).abs().mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
        sched.step()
        loss_avg = loss.item() if loss_avg is None else 0.98 * loss_avg + 0.02 * loss.item()
        if curve_due(step + 1, config.steps):
            curve.append((step + 1, loss_avg))
            if progress is not None:
                progress(step + 1, loss_avg)
    return model, xn, yn, curve, round(time.perf_counter() - t0, 1)


class MultiTaskPolicy(BCPolicy):
    """A multi-task checkpoint as an evaluation policy: :meth:`bind` takes the env's instruction and its embedding
    (one it learned, or ``embed``'s for a new one)."""

    def __init__(self, path: Path | str, embed: Embed | None = None):
        self.embed = embed
        super().__init__(path)

    def __post_init__(self):
        ckpt = load_checkpoint(self.path)
        tasks, world_dim = ckpt.get("tasks"), ckpt.get("world_dim")
        emb = ckpt["model"].pop("_embeddings", None)
        if ckpt.get("kind") != KIND or not isinstance(tasks, dict) or not all(
                isinstance(k, str) and isinstance(v, str) for k, v in tasks.items()):
            raise _bad(self.path, f"not a multi-task checkpoint (kind {ckpt.get('kind')!r}, tasks a mapping of task "
                                  "id to instruction)")
        if type(world_dim) is not int or not 0 <= world_dim <= MAX_FEATURES:
            raise _bad(self.path, f"world_dim {world_dim!r} must be an integer from 0 to {MAX_FEATURES}")
        if emb is None or emb.ndim != 2 or len(emb) != len(tasks) or not emb.is_floating_point() \
                or not bool(torch.isfinite(emb).all()):
            raise _bad(self.path, "_embeddings must be a finite [tasks, E] float tensor, a row per task")
        names = ckpt["names"].get(STATE) if isinstance(ckpt["names"], dict) else None
        velocity = ckpt["config"].get("joint_velocity", True)  # checkpoints from before the switch read them
        if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
            raise _bad(self.path, f"names[{STATE!r}] must be the (non-empty) list of the state's entry names")
        if type(velocity) is not bool:
            raise _bad(self.path, f"config.joint_velocity {velocity!r} must be true or false")
        self.state_names, self.keep = names, state_columns(names, velocity)
        self.instructions = dict(zip(tasks.values(), emb.numpy().astype(np.float32), strict=True))
        self.world_dim = world_dim
        self.ckpt = ckpt
        cfg = ckpt["config"]
        self.chunk, self.decay = cfg["chunk"], cfg["ensemble_decay"]
        n_in, n_out = len(ckpt["x_mean"]), len(ckpt["a_mean"]) * self.chunk
        self.model = build_network(lambda: _mlp(n_in, n_out, cfg["hidden"], cfg["layers"]), ckpt["model"], self.path)
        self.x = Normalizer(ckpt["x_mean"], ckpt["x_std"])
        self.a = Normalizer(ckpt["a_mean"], ckpt["a_std"])
        want = len(ckpt["x_mean"]) - len(self.keep) - world_dim - 1
        if want != emb.shape[1]:
            raise _bad(self.path, f"its inputs leave {want} values for an instruction embedding of {emb.shape[1]}")

    @property
    def tasks(self) -> dict[str, str]:
        return dict(self.ckpt["tasks"])

    def bind(self, env) -> None:
        """Take the instruction of ``env``'s task and its embedding; keep the action bounds."""
        self.emb = instruction_embedding(self, env)
        text = env.unwrapped.task_spec.instruction
        if len(self.emb) != len(next(iter(self.instructions.values()))):
            raise PolicyTaskError(f"the embedding of {text!r} has {len(self.emb)} values, not the checkpoint's")
        self.low, self.high = env.action_space.low, env.action_space.high

    def features(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        world, state = obs[ENVIRONMENT_STATE][None], obs[STATE][None]
        if world.shape[1] > self.world_dim:
            raise PolicyTaskError(f"the env's environment state has {world.shape[1]} values; the policy learned "
                                  f"at most {self.world_dim}")
        if state.shape[1] != len(self.state_names):
            raise PolicyTaskError(f"the env's state has {state.shape[1]} values; the policy learned "
                                  f"{len(self.state_names)} ({self.state_names[0]} ... {self.state_names[-1]})")
        return _inputs(state[:, self.keep], world, np.array([self.t], np.float32), self.emb, self.world_dim)


def is_multitask(path: Path | str) -> bool:
    """Whether the checkpoint at ``path`` is a multi-task one (read with the checkpoint's own checks)."""
    return load_checkpoint(path).get("kind") == KIND


__all__ = ["KIND", "FrameSampler", "MultiTaskConfig", "MultiTaskPolicy", "TaskData", "embed_tasks",
           "instruction_embedding", "is_multitask", "load_tasks", "state_columns", "train"]
