"""Behaviour cloning with action chunks: the imitation baseline GenDex datasets are measured with.

The policy sees what a GenDex dataset records and :class:`~gendex_envs.observation.LeRobotObservation` gives in the
env: ``observation.state`` (joint positions and velocities), ``observation.environment_state`` (object poses,
joint positions, goal) and the episode's step count; it predicts the next :attr:`BCConfig.chunk` actions (absolute
joint targets). An MLP, trained with an L1 loss on normalized actions (as ACT is), with a little Gaussian noise on
the normalized inputs. At run time every step's prediction is kept, and the action executed at step ``t`` is the
exponentially weighted mean of every chunk's prediction for ``t`` (ACT's temporal ensembling), which keeps the arm
smooth where consecutive predictions disagree.

A checkpoint (``bc.pt``) holds the weights, the normalization, the feature names it was trained on, the dataset's
task id, ``gym.make`` keyword arguments and the reset seeds of the episodes it learned from (an evaluation refuses
seeds a policy was trained on).

A checkpoint may come from anyone, so it holds only tensors and JSON values (str, int, float, bool, None, lists and
dicts of them) and is read with ``torch.load(weights_only=True)``: nothing in it can run code. The network is the
known MLP :func:`_mlp` built from the checkpoint's bounded ``config``, and its weights load strictly. Checkpoints of
``CHECKPOINT_FORMAT`` 1 (numpy arrays, which need pickle) are refused with :class:`~gendex_envs.errors.PolicyError`;
:func:`resave_trusted_checkpoint` converts one the user trusts.
"""

from __future__ import annotations

import io
import json
import logging
import time
import zipfile
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import torch
from gymnasium.envs.registration import parse_env_id
from torch import nn

from gendex.imitation.frames import DatasetReadError, Frames, lerobot_root, load_frames
from gendex_envs.atomic_io import atomic_path
from gendex_envs.errors import GenDexError, PolicyError
from gendex_envs.observation import ENVIRONMENT_STATE, STATE
from gendex_envs.saved_tensors import check_tensor_sizes

log = logging.getLogger(__name__)


class PolicyTaskError(GenDexError, ValueError):
    """A BC checkpoint asked to act in a task it did not learn."""


def _task_name(env_id: str) -> str:
    """``GenDex/PickUpBottle-v2`` -> ``GenDex/PickUpBottle``: a checkpoint may act in another version of its task
    (the same objects and spaces; a version changes randomization or success)."""
    ns, name, _ = parse_env_id(env_id)
    return f"{ns}/{name}" if ns else name

CHECKPOINT = "bc.pt"
CHECKPOINT_FORMAT = 2
"""2: tensors and JSON values only (``weights_only``); 1 (no ``format`` key): numpy arrays, pickled."""
MAX_CHECKPOINT_BYTES = 512_000_000
"""A checkpoint file (the default 3 x 512 MLP is about 4 MB)."""
ENV_KWARGS = {"control_mode": str, "control_joint": str, "obs_mode": str, "sensor_resolution": int,
              "reconfiguration_freq": int, "sensors": list}
"""The ``gym.make`` keyword arguments a checkpoint may ask for (those a GenDex dataset records), with their types:
a checkpoint never chooses ``trust_remote_code``, start states or any other argument."""
MAX_RECORDS = 10_000
"""Records in a checkpoint's torch archive (about 30 for the default MLP)."""
MAX_HIDDEN, MAX_LAYERS, MAX_CHUNK, MAX_FEATURES = 8192, 16, 1000, 100_000
"""Bounds of a checkpoint's ``config`` and input/action sizes, checked before a network is built."""
STEP_SCALE = 200.0
"""The step-count input is ``step / STEP_SCALE``."""


CURVE_POINTS = 50  # a training run's learning curve: the smoothed loss at about this many evenly spaced steps


def curve_due(step: int, steps: int) -> bool:
    """Whether 1-based ``step`` of a ``steps``-step run is a point of its learning curve: every ``steps //
    CURVE_POINTS`` steps (at least every step, at most 1 000 apart) and the last."""
    every = min(1000, max(1, steps // CURVE_POINTS))
    return step % every == 0 or step == steps


@dataclass(frozen=True)
class BCConfig:
    chunk: int = 10
    """Actions predicted per step."""
    hidden: int = 512
    layers: int = 3
    steps: int = 20_000
    """Gradient steps."""
    batch: int = 256
    lr: float = 1e-3
    weight_decay: float = 1e-4
    obs_noise: float = 0.02
    """Std of the Gaussian noise added to normalized inputs while training."""
    ensemble_decay: float = 0.1
    """Temporal ensembling: the weight of a prediction made k steps ago is exp(-decay * k)."""
    seed: int = 0


@dataclass
class Normalizer:
    mean: np.ndarray
    std: np.ndarray

    @classmethod
    def fit(cls, x: np.ndarray) -> Normalizer:
        return cls(x.mean(0).astype(np.float32), np.maximum(x.std(0), 1e-3).astype(np.float32))

    def __call__(self, x):
        return (x - self.mean) / self.std

    def inverse(self, x):
        return x * self.std + self.mean


def _mlp(n_in: int, n_out: int, hidden: int, layers: int) -> nn.Sequential:
    mods: list[nn.Module] = []
    for k in range(layers):
        mods += [nn.Linear(n_in if k == 0 else hidden, hidden), nn.LayerNorm(hidden), nn.GELU()]
    return nn.Sequential(*mods, nn.Linear(hidden, n_out))


def build_network(make: Callable[[], nn.Module], weights: dict[str, torch.Tensor], path: Path | str) -> nn.Module:
    """The network ``make()`` builds, with a checkpoint's ``weights`` loaded strictly. Its shape is laid out on the
    meta device first (no memory) and compared with the weights' names and shapes: a checkpoint's config sizes the
    network, and a small hostile file whose config asks for 16 layers of 8192 units would otherwise have the loader
    allocate gigabytes before the weights are found not to fit. :class:`PolicyError` naming the first mismatch."""
    with torch.device("meta"):
        layout = {k: tuple(v.shape) for k, v in make().state_dict().items()}
    given = {k: tuple(v.shape) for k, v in weights.items()}
    if layout != given:
        wrong = sorted(set(layout) ^ set(given)) or [k for k in layout if layout[k] != given[k]]
        k = wrong[0]
        raise _bad(path, f"its weights do not fit the network its config describes: {k} is "
                         f"{given.get(k, 'missing')} in the file, {layout.get(k, 'not a parameter')} by the config")
    model = make()
    model.load_state_dict(weights, strict=True)
    return model.eval()


def _inputs(state: np.ndarray, world: np.ndarray, step: np.ndarray) -> np.ndarray:
    return np.concatenate([state, world, (step / STEP_SCALE)[:, None]], axis=1).astype(np.float32)


def _chunk_targets(frames: Frames, chunk: int) -> np.ndarray:
    """[F, chunk, A]: each frame's next ``chunk`` actions within its episode (the last one repeated at the end)."""
    out = np.empty((len(frames.action), chunk, frames.action.shape[1]), np.float32)
    starts = np.flatnonzero(np.r_[True, frames.episode[1:] != frames.episode[:-1]])
    ends = np.r_[starts[1:], len(frames.action)]
    for s, e in zip(starts, ends, strict=True):
        idx = np.minimum(np.arange(s, e)[:, None] + np.arange(chunk)[None, :], e - 1)
        out[s:e] = frames.action[idx]
    return out


def _dataset_meta(path: Path) -> dict:
    meta = lerobot_root(path) / "meta" / "gendex.json"
    if not meta.is_file():
        raise DatasetReadError(f"{meta} is missing: the dataset does not say which env and seeds it comes from "
                               "(datasets from gendex collect or gendex dataset build carry it)")
    return json.loads(meta.read_text())


def train(dataset: Path | str, out: Path | str, demos: int | None = None, config: BCConfig = BCConfig(),
          progress: Callable[[int, float], None] | None = None) -> Path:
    """Train on the first ``demos`` episodes of ``dataset``; writes ``<out>/bc.pt`` and returns its path."""
    frames = load_frames(dataset, demos)
    meta = _dataset_meta(Path(dataset))
    threads = torch.get_num_threads()
    torch.set_num_threads(1)  # a small MLP: threads only contend (58 vs 3 ms a step on 2 busy cores, measured)
    try:
        return _train(frames, meta, Path(dataset), Path(out), config, progress)
    finally:
        torch.set_num_threads(threads)


def _train(frames: Frames, meta: dict, dataset: Path, out: Path, config: BCConfig,
           progress: Callable[[int, float], None] | None) -> Path:
    torch.manual_seed(config.seed)
    rng = np.random.default_rng(config.seed)
    x = _inputs(frames.state, frames.environment_state, frames.frame.astype(np.float32))
    y = _chunk_targets(frames, config.chunk).reshape(len(x), -1)
    xn, yn = Normalizer.fit(x), Normalizer.fit(frames.action)
    xt = torch.as_tensor(xn(x))
    yt = torch.as_tensor(yn(y.reshape(len(x), config.chunk, -1)).reshape(len(x), -1))
    model = _mlp(x.shape[1], y.shape[1], config.hidden, config.layers)
    opt = torch.optim.AdamW(model.parameters(), lr=config.lr, weight_decay=config.weight_decay)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, config.steps)
    t0, loss_avg = time.perf_counter(), None
    for step in range(config.steps):
        idx = torch.as_tensor(rng.integers(len(xt), size=min(config.batch, len(xt))))
        inp = xt[idx] + config.obs_noise * torch.randn(len(idx), xt.shape[1])
        loss = (model(inp) - yt[idx]).abs().mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
        sched.step()
        value = loss.item()
        loss_avg = value if loss_avg is None else 0.98 * loss_avg + 0.02 * value
        if progress is not None and (step + 1) % 1000 == 0:
            progress(step + 1, loss_avg)
    out.mkdir(parents=True, exist_ok=True)
    seeds = meta.get("episode_seeds", [])[:frames.episodes]
    norm = {"x_mean": xn.mean, "x_std": xn.std, "a_mean": yn.mean, "a_std": yn.std}
    info = {"config": asdict(config), "names": frames.names, "task_id": meta["task_id"],
            "env_kwargs": meta["env_kwargs"], "training_seeds": [int(s) for s in seeds], "demos": int(frames.episodes),
            "frames": len(x), "dataset": str(dataset), "final_loss": None if loss_avg is None else float(loss_avg),
            "seconds": round(time.perf_counter() - t0, 1)}
    path = out / CHECKPOINT
    save_checkpoint(path, model.state_dict(), norm, info)
    (out / "bc.json").write_text(json.dumps(info, indent=1) + "\n")
    log.info("trained BC on %d demos (%d frames) of %s in %.0f s, loss %.4f -> %s", frames.episodes, len(x),
             meta["task_id"], info["seconds"], loss_avg, path)
    return path


_NORMS = ("x_mean", "x_std", "a_mean", "a_std")
_INFO = ("config", "names", "task_id", "env_kwargs", "training_seeds", "demos", "frames", "dataset", "final_loss",
         "seconds")


MAX_METADATA_DEPTH = 32
"""Nesting of a checkpoint's JSON metadata (what ``gendex bc train`` writes nests 3 levels)."""


def _json_safe(value) -> bool:
    """Only str/int/float/bool/None and lists/dicts (str keys) of them: what ``weights_only`` needs no pickle for.
    A tree, as JSON is: a pickle's memo can make a list that holds itself (the walk would never end) or share one
    list along 2**N paths, so a container met twice is refused, and so is nesting past :data:`MAX_METADATA_DEPTH`."""
    stack, seen = [(value, 0)], set()
    while stack:
        v, depth = stack.pop()
        if isinstance(v, dict | list | tuple):
            if depth >= MAX_METADATA_DEPTH or (v and id(v) in seen):  # (empty ones may be one shared object)
                return False
            seen.add(id(v))
        if isinstance(v, dict):
            if not all(isinstance(k, str) for k in v):
                return False
            stack.extend((x, depth + 1) for x in v.values())
        elif isinstance(v, (list, tuple)):
            stack.extend((x, depth + 1) for x in v)
        elif not (v is None or type(v) in (str, int, float, bool)):
            return False
    return True


def save_checkpoint(path: Path | str, weights: dict, norm: dict, info: dict) -> Path:
    """Write a checkpoint of :data:`CHECKPOINT_FORMAT` (tensors and JSON values only, module doc)."""
    if not _json_safe(info):
        raise PolicyError(f"{path}: a BC checkpoint's metadata must be JSON values (str, int, float, lists, dicts)")
    ckpt = {"format": CHECKPOINT_FORMAT, "model": {k: v.detach().cpu() for k, v in weights.items()},
            **{k: torch.as_tensor(np.asarray(norm[k], np.float32)) for k in _NORMS}, **info}
    path = Path(path)
    with atomic_path(path) as tmp:
        torch.save(ckpt, tmp)
    return path


def _bad(path, problem: str) -> PolicyError:
    return PolicyError(f"BC checkpoint {path}: {problem}")


def _check_archive(raw: bytes, path: Path) -> None:
    """``torch.save``'s zip format, every record stored uncompressed within the file's bytes (at most
    ``MAX_RECORDS``): torch's reader would otherwise inflate a record to whatever size the archive declares."""
    try:
        infos = zipfile.ZipFile(io.BytesIO(raw)).infolist()
    except (zipfile.BadZipFile, ValueError, EOFError):
        raise _bad(path, "not a torch archive (the zip format torch.save writes)") from None
    if len(infos) > MAX_RECORDS:
        raise _bad(path, f"{len(infos)} records; at most MAX_RECORDS = {MAX_RECORDS} are allowed")
    if any(i.compress_type != zipfile.ZIP_STORED for i in infos) or sum(i.file_size for i in infos) > len(raw):
        raise _bad(path, "compressed or oversized records; torch.save stores every record uncompressed")


def load_checkpoint(path: Path | str) -> dict:
    """A checkpoint read with ``torch.load(weights_only=True)`` and checked (module doc): the normalization as
    float32 numpy arrays, the weights as tensors. :class:`PolicyError` naming the file when it needs pickle, is
    malformed, out of bounds or not finite."""
    path = Path(path)
    if not path.is_file():
        raise _bad(path, "no such file")
    size = path.stat().st_size
    if size > MAX_CHECKPOINT_BYTES:
        raise _bad(path, f"{size} bytes; at most MAX_CHECKPOINT_BYTES = {MAX_CHECKPOINT_BYTES} are allowed")
    raw = path.read_bytes()
    _check_archive(raw, path)
    try:
        ckpt = torch.load(io.BytesIO(raw), map_location="cpu", weights_only=True)
    except Exception as exc:
        text = str(exc).strip().splitlines()
        raise _bad(path, f"it holds objects that only pickle can load, which can run code from the file "
                         f"({type(exc).__name__}: {(text[-1] if text else '')[:300]}). GenDex loads checkpoints "
                         f"of format {CHECKPOINT_FORMAT} (tensors and JSON values); retrain with `gendex bc train`, "
                         "or, only if you trust the file, convert it with "
                         "gendex.imitation.bc.resave_trusted_checkpoint(PATH)") from None
    if not isinstance(ckpt, dict) or ckpt.get("format") != CHECKPOINT_FORMAT:
        found = ckpt.get("format") if isinstance(ckpt, dict) else type(ckpt).__name__
        raise _bad(path, f"format {found!r}; this GenDex reads format {CHECKPOINT_FORMAT}")
    missing = [k for k in ("model", *_NORMS, *_INFO) if k not in ckpt]
    if missing:
        raise _bad(path, f"missing {missing}")
    if not _json_safe({k: ckpt[k] for k in _INFO}):
        raise _bad(path, f"{list(_INFO)} must be JSON values")
    weights = ckpt["model"]
    if not isinstance(weights, dict) or not all(isinstance(k, str) and isinstance(v, torch.Tensor)
                                                for k, v in weights.items()):
        raise _bad(path, "model must map names to finite floating-point tensors")
    tensors = [*weights.items(), *((k, ckpt[k]) for k in _NORMS if isinstance(ckpt[k], torch.Tensor))]
    check_tensor_sizes(tensors, path, PolicyError, MAX_CHECKPOINT_BYTES)  # before isfinite materialises a view
    if not all(v.is_floating_point() and bool(torch.isfinite(v).all()) for v in weights.values()):
        raise _bad(path, "model must map names to finite floating-point tensors")
    for k in _NORMS:
        v = ckpt[k]
        if not isinstance(v, torch.Tensor) or v.ndim != 1 or not 0 < len(v) <= MAX_FEATURES \
                or not v.is_floating_point() or not bool(torch.isfinite(v).all()):
            raise _bad(path, f"{k} must be a 1-D finite float tensor of 1 to MAX_FEATURES = {MAX_FEATURES} values")
        ckpt[k] = v.numpy().astype(np.float32)
    if len(ckpt["x_std"]) != len(ckpt["x_mean"]) or len(ckpt["a_std"]) != len(ckpt["a_mean"]) \
            or (ckpt["x_std"] <= 0).any() or (ckpt["a_std"] <= 0).any():
        raise _bad(path, "x_std and a_std must match their means in length and be > 0")
    cfg = ckpt["config"]
    bounds = {"chunk": MAX_CHUNK, "hidden": MAX_HIDDEN, "layers": MAX_LAYERS}
    for key, bound in bounds.items():
        value = cfg.get(key) if isinstance(cfg, dict) else None
        if type(value) is not int or not 1 <= value <= bound:
            raise _bad(path, f"config.{key} {value!r} must be an integer from 1 to {bound}")
    decay = cfg.get("ensemble_decay")
    if type(decay) not in (int, float) or not 0 <= decay <= 100:
        raise _bad(path, f"config.ensemble_decay {decay!r} must be a number from 0 to 100")
    if not isinstance(ckpt["task_id"], str) or not isinstance(ckpt["env_kwargs"], dict) \
            or not all(type(s) is int for s in ckpt["training_seeds"]):
        raise _bad(path, "task_id must be a string, env_kwargs a mapping and training_seeds integers")
    for key, value in ckpt["env_kwargs"].items():
        if key not in ENV_KWARGS or type(value) is not ENV_KWARGS[key]:
            raise _bad(path, f"env_kwargs {key}={str(value)[:60]!r}: a checkpoint may only set "
                             f"{', '.join(f'{k} ({t.__name__})' for k, t in ENV_KWARGS.items())}")
        if key == "sensors":
            _check_sensors(path, value)
    return ckpt


def _check_sensors(path: Path, value: list) -> None:
    """A checkpoint's ``sensors``: names of the env's cameras (a list the dataset recorded)."""
    from gendex_envs.cameras import check_sensors
    from gendex_envs.errors import RenderModeError

    try:
        if len(value) > 8 or not all(type(v) is str for v in value):
            raise RenderModeError("sensors must be a short list of camera names")
        check_sensors(value)
    except RenderModeError as exc:
        raise _bad(path, f"env_kwargs {exc}") from None


def resave_trusted_checkpoint(path: Path | str, out: Path | str | None = None) -> Path:
    """Convert a format-1 checkpoint (numpy arrays) to the current format. It unpickles the file, which runs any
    code in it: call it only on a file you made yourself or trust like your own code."""
    old = torch.load(Path(path), map_location="cpu", weights_only=False)
    info = {k: old[k] for k in _INFO}
    info["training_seeds"] = [int(s) for s in info["training_seeds"]]
    info["final_loss"] = None if info["final_loss"] is None else float(info["final_loss"])
    for k in ("demos", "frames"):
        info[k] = int(info[k])
    return save_checkpoint(Path(out) if out is not None else Path(path), old["model"],
                           {k: old[k] for k in _NORMS}, info)


@dataclass
class BCPolicy:
    """A trained checkpoint as an evaluation policy (an agent of :func:`gendex.episode_loop.run_episode`, which
    ``gendex eval`` runs it in): ``bind(env)``, ``reset()``, ``act(obs)`` on LeRobotObservation's dict."""

    path: Path | str
    ckpt: dict = field(init=False, repr=False)

    def __post_init__(self):
        self.ckpt = load_checkpoint(self.path)
        cfg = self.ckpt["config"]
        self.chunk, self.decay = cfg["chunk"], cfg["ensemble_decay"]
        n_in, n_out = len(self.ckpt["x_mean"]), len(self.ckpt["a_mean"]) * self.chunk
        self.model = build_network(lambda: _mlp(n_in, n_out, cfg["hidden"], cfg["layers"]), self.ckpt["model"],
                                   self.path)
        self.x = Normalizer(self.ckpt["x_mean"], self.ckpt["x_std"])
        self.a = Normalizer(self.ckpt["a_mean"], self.ckpt["a_std"])

    @property
    def task_id(self) -> str:
        return self.ckpt["task_id"]

    @property
    def env_kwargs(self) -> dict:
        """The ``gym.make`` keyword arguments of the data it learned from (its action space)."""
        return {k: v for k, v in self.ckpt["env_kwargs"].items() if k != "reconfiguration_freq"}

    @property
    def training_seeds(self) -> list[int]:
        return list(self.ckpt["training_seeds"])

    def bind(self, env) -> None:
        """Check that ``env`` is the task the checkpoint learned, and keep its action bounds: an action is clipped to
        them (joint limits of absolute targets)."""
        env_id = getattr(getattr(env, "spec", None), "id", None)
        if env_id is not None and _task_name(env_id) != _task_name(self.task_id):
            raise PolicyTaskError(f"BC checkpoint {self.path} learned {self.task_id}, not {env_id}: give one "
                                  f"checkpoint per task (bc:PATH,PATH,...)")
        if env_id is not None and env_id != self.task_id:
            log.info("BC checkpoint %s learned %s; acting in %s, another version of the task", self.path,
                     self.task_id, env_id)
        self.low, self.high = env.action_space.low, env.action_space.high

    def reset(self) -> None:
        self.t = 0
        self.pending: list[tuple[int, np.ndarray]] = []  # (step it was predicted at, [chunk, A])

    def features(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """[1, inputs]: what the network reads at this step (before normalization)."""
        return _inputs(obs[STATE][None], obs[ENVIRONMENT_STATE][None], np.array([self.t], np.float32))

    @torch.no_grad()
    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        return self._ensemble(self.model(torch.as_tensor(self.x(self.features(obs)))).numpy().reshape(self.chunk, -1))

    def _ensemble(self, pred: np.ndarray) -> np.ndarray:
        """The action of this step from every kept chunk's prediction for it (temporal ensembling; module doc),
        ``pred`` being this step's [chunk, A] prediction (normalized)."""
        self.pending = [(t0, c) for t0, c in self.pending if self.t - t0 < self.chunk] + [(self.t, pred)]
        ages = np.array([self.t - t0 for t0, _ in self.pending], np.float32)
        w = np.exp(-self.decay * ages)
        mean = sum(wi * c[self.t - t0] for wi, (t0, c) in zip(w, self.pending, strict=True)) / w.sum()
        self.t += 1
        action = self.a.inverse(mean).astype(np.float32)
        return np.clip(action, self.low, self.high) if hasattr(self, "low") else action


class BCPolicies:
    """Several checkpoints, one per task, as one evaluation policy (``--policy bc:PATH,PATH,...``): :meth:`bind`
    picks the checkpoint of the env's task, or fails naming the tasks it has."""

    def __init__(self, paths: list[Path | str]):
        self.by_task: dict[str, BCPolicy] = {}
        for path in paths:
            policy = BCPolicy(path)
            if policy.task_id in self.by_task:
                raise PolicyTaskError(f"two BC checkpoints for {policy.task_id}: {self.by_task[policy.task_id].path} "
                                      f"and {path}")
            self.by_task[policy.task_id] = policy
        self.active: BCPolicy | None = None

    @property
    def training_seeds(self) -> list[int]:
        return sorted({s for p in self.by_task.values() for s in p.training_seeds})

    def bind(self, env) -> None:
        env_id = getattr(getattr(env, "spec", None), "id", None)
        same = [k for k in self.by_task if _task_name(k) == _task_name(str(env_id))]
        if env_id not in self.by_task and len(same) != 1:
            raise PolicyTaskError(f"no BC checkpoint for {env_id}; checkpoints: {sorted(self.by_task)}")
        self.active = self.by_task[env_id if env_id in self.by_task else same[0]]
        self.active.bind(env)

    def reset(self) -> None:
        self.active.reset()

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        return self.active.act(obs)


def load_policy(spec: str, embed: Callable[[list[str]], np.ndarray] | None = None) -> BCPolicy | BCPolicies:
    """``PATH`` (one checkpoint, single- or multi-task) or ``PATH,PATH,...`` (one per task), as ``--policy bc:...``
    gives them; ``embed``: a multi-task policy's encoder for an instruction it did not learn."""
    paths = [s for s in spec.split(",") if s]
    if not paths:
        raise PolicyTaskError("bc: needs a checkpoint path (bc:PATH or bc:PATH,PATH,...)")
    kind = load_checkpoint(paths[0]).get("kind") if len(paths) == 1 else None
    if kind == "multitask":
        from gendex.imitation.multitask import MultiTaskPolicy

        return MultiTaskPolicy(paths[0], embed)
    if kind == "pixels":
        from gendex.imitation.pixels import PixelPolicy

        return PixelPolicy(paths[0], embed)
    return BCPolicy(paths[0]) if len(paths) == 1 else BCPolicies(paths)


__all__ = ["BCConfig", "BCPolicies", "BCPolicy", "CHECKPOINT", "CHECKPOINT_FORMAT", "PolicyTaskError",
           "load_checkpoint", "load_policy", "resave_trusted_checkpoint", "save_checkpoint", "train"]
