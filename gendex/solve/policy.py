"""Run a trained stage policy inside an env of any control mode.

A policy is trained on the stage's own env (``TaskEnv(stage=...)``): observation = ManiSkill's flat ``state`` of that
env (agent qpos, qvel and controller targets, then the env's extras with the stage module's ``_get_obs_extra``),
normalized with the running mean and variance saved in the policy's record; action = normalized joint-target deltas
of the stage's ``control_joint`` group. :class:`StagePolicy` rebuilds exactly that observation on another env of the
same task (the stage executor's, which drives every joint with absolute targets,
:meth:`~gendex_envs.task_env.TaskEnv.state_observation`) and turns the policy's deltas into absolute targets for all
joints, so one policy file serves training, evaluation and data collection. Everything is batched over
``num_envs``. Where the files lie is the task version's business (:class:`~gendex_envs.task_version.PolicyFiles`).

A policy file may come from an untrusted task folder, so it is loaded as *weights plus a known architecture*, never
by unpickling: :func:`read_policy_weights` reads only the ``policy.pth`` entry of the stable-baselines3 zip with
``torch.load(weights_only=True)`` (the zip's ``data`` entry, which holds cloudpickle, is never read), and
:func:`build_policy_network` builds the MLP actor-critic ``gendex train`` creates (the record's ``architecture``;
derived from its ``preset`` for records written before it was recorded) and loads the weights strictly. The result
is the same ``ActorCriticPolicy`` class with the same weights that ``PPO.load`` gave, so its actions are identical.
Sizes are bounded before anything is read (the ``MAX_POLICY_*`` constants, docs/security.md).
"""

from __future__ import annotations

import io
import logging
import math
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from gendex_envs.agents.ur10e_shadow import delta_limits, free_joints
from gendex_envs.errors import PolicyError, StageError
from gendex_envs.saved_tensors import check_tensor_sizes
from gendex_envs.success import Judge
from gendex_envs.task_version import PolicyFiles, TaskVersion

log = logging.getLogger(__name__)

POLICY_FORMAT = 1
"""Version of a policy's JSON record; bumped when the observation or action layout changes."""
WHOLE_TASK = "task"
"""Stage name of a policy trained on the whole task (every joint, the task's reward and success)."""

ARCHITECTURE_KIND = "sb3-mlp-actor-critic"
"""The only network a policy file may hold: stable-baselines3's ``ActorCriticPolicy`` with separate MLP policy and
value nets (``net_arch``, ``activation``), a Gaussian action head over a Box(-1, 1) action space."""
ACTIVATIONS = {"relu": torch.nn.ReLU, "tanh": torch.nn.Tanh}
"""Activation names a record may give -> module (every preset trains with ReLU)."""
WEIGHTS_ENTRY = "policy.pth"
"""The entry of a stable-baselines3 zip that holds the policy's state dict (the only entry GenDex reads)."""
MAX_POLICY_RECORD_BYTES = 1_000_000
"""A policy's JSON record (about 9 KB for 136 observations)."""
MAX_POLICY_ZIP_ENTRIES = 64
"""Entries in a policy zip (stable-baselines3 writes 6)."""
MAX_POLICY_WEIGHTS_BYTES = 256_000_000
"""Uncompressed size of ``policy.pth`` (0.8 MB for the cpu preset; about 30 MB for the paper's [1024, 1024, 512]
at 1000 observations)."""
MAX_TORCH_RECORDS = 10_000
"""Records in the torch archive inside ``policy.pth`` (19 for the cpu preset); each must be stored uncompressed,
as ``torch.save`` writes them, so nothing in it inflates past the bytes already bounded."""
MAX_OBS_DIM = 10_000
MAX_ACTION_DIM = 64
MAX_LAYERS = 8
MAX_LAYER_WIDTH = 4096
"""Bounds of a recorded architecture, checked before a network is built (the paper preset is 3 layers of <= 1024)."""


def stage_observation(env, judge: Judge, info: dict | None = None) -> torch.Tensor:
    """[N, D] the flat ``state`` observation a stage env judged by ``judge`` would return for ``env``'s state
    (``info``: ``judge.evaluate`` of this state, if the caller has it already)."""
    return env.unwrapped.state_observation(judge, info)


def success_hold_steps(version: TaskVersion, stage: str) -> int:
    """Consecutive steps ``stage``'s success must hold in its env (:attr:`StagePolicy.hold_steps`)."""
    own = stage != WHOLE_TASK and version.stage(stage)[1].success is not None
    return 1 if own else max(1, version.spec.success.hold_steps)


def _refuse(path, problem: str) -> PolicyError:
    return PolicyError(f"{path}: {problem}")


def read_policy_record(path: str | Path) -> dict:
    """A policy's JSON record, parsed with the bounded loader and checked: format, control joint group, observation
    normalization (finite numbers, as many variances as means); :class:`PolicyError` naming what is wrong."""
    from gendex_envs.agents.ur10e_shadow import CONTROL_JOINT_GROUPS
    from gendex_envs.typed_yaml import parse_json_bounded

    path = Path(path)
    size = path.stat().st_size
    if size > MAX_POLICY_RECORD_BYTES:
        raise _refuse(path, f"policy record of {size} bytes; at most MAX_POLICY_RECORD_BYTES = "
                            f"{MAX_POLICY_RECORD_BYTES} are allowed")
    try:
        meta = parse_json_bounded(path.read_bytes(), str(path), max_bytes=MAX_POLICY_RECORD_BYTES,
                                  max_string=None, max_nodes=4 * MAX_OBS_DIM + 10_000)
    except ValueError as exc:
        raise _refuse(path, f"not a readable policy record ({exc})") from None
    if not isinstance(meta, dict):
        raise _refuse(path, "a policy record is a JSON object")
    if meta.get("format") != POLICY_FORMAT:
        raise _refuse(path, f"policy format {meta.get('format')!r}, this GenDex reads {POLICY_FORMAT}")
    if meta.get("control_joint") not in CONTROL_JOINT_GROUPS:
        raise _refuse(path, f"control_joint {meta.get('control_joint')!r} is not one of {sorted(CONTROL_JOINT_GROUPS)}")
    norm = meta.get("obs_norm")
    if not isinstance(norm, dict) or not all(isinstance(norm.get(k), list) for k in ("mean", "var")):
        raise _refuse(path, "obs_norm must hold lists `mean` and `var`")
    n = len(norm["mean"])
    if not 0 < n <= MAX_OBS_DIM or len(norm["var"]) != n:
        raise _refuse(path, f"obs_norm: {n} means and {len(norm['var'])} variances; both must have the same "
                            f"length, 1 to MAX_OBS_DIM = {MAX_OBS_DIM}")
    values = [*norm["mean"], *norm["var"], norm.get("clip")]
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in values):
        raise _refuse(path, "obs_norm: mean, var and clip must be finite numbers")
    if min(norm["var"]) < 0 or not norm["clip"] > 0:
        raise _refuse(path, "obs_norm: variances must be >= 0 and clip > 0")
    return meta


def policy_architecture(meta: dict, action_dim: int | None = None) -> dict:
    """The network of a policy record: its ``architecture`` entry, or (records written before it was recorded)
    the one ``gendex train`` built from its ``preset``: ``net_arch`` hidden layers with ReLU for both the policy and
    the value net, ``obs_dim`` observations, one action per free joint of its ``control_joint`` group."""
    if "architecture" in meta:
        return meta["architecture"]
    preset = meta.get("preset") if isinstance(meta.get("preset"), dict) else {}
    return dict(kind=ARCHITECTURE_KIND, net_arch=preset.get("net_arch"), activation="relu",
                obs_dim=len(meta["obs_norm"]["mean"]),
                action_dim=action_dim if action_dim is not None else len(free_joints(meta["control_joint"])))


def architecture_of(net_arch, obs_dim: int, action_dim: int, activation: str = "relu") -> dict:
    """What a policy record says about the network ``gendex train`` made (:func:`policy_architecture`)."""
    return dict(kind=ARCHITECTURE_KIND, net_arch=[int(w) for w in net_arch], activation=activation,
                obs_dim=int(obs_dim), action_dim=int(action_dim))


def _check_architecture(arch, path) -> dict:
    if not isinstance(arch, dict) or arch.get("kind") != ARCHITECTURE_KIND:
        raise _refuse(path, f"architecture {arch!r}: GenDex loads only {ARCHITECTURE_KIND!r} networks")
    if set(arch) != {"kind", "net_arch", "activation", "obs_dim", "action_dim"}:
        raise _refuse(path, f"architecture keys {sorted(arch)}; expected kind, net_arch, activation, obs_dim, "
                            "action_dim")
    net, ints = arch["net_arch"], lambda v: isinstance(v, int) and not isinstance(v, bool)
    if (not isinstance(net, list) or not 1 <= len(net) <= MAX_LAYERS
            or not all(ints(w) and 1 <= w <= MAX_LAYER_WIDTH for w in net)):
        raise _refuse(path, f"net_arch {net!r}: 1 to MAX_LAYERS = {MAX_LAYERS} layers of 1 to MAX_LAYER_WIDTH = "
                            f"{MAX_LAYER_WIDTH} units")
    if arch["activation"] not in ACTIVATIONS:
        raise _refuse(path, f"activation {arch['activation']!r} is not one of {sorted(ACTIVATIONS)}")
    for key, bound in (("obs_dim", MAX_OBS_DIM), ("action_dim", MAX_ACTION_DIM)):
        if not ints(arch[key]) or not 1 <= arch[key] <= bound:
            raise _refuse(path, f"{key} {arch[key]!r} must be an integer from 1 to {bound}")
    return arch


def check_torch_archive(raw: bytes, path, error: type[Exception], max_records: int) -> None:
    """Refuse (``error`` naming ``path``) bytes that are not ``torch.save``'s zip format with at most
    ``max_records`` records, each stored uncompressed and within the bytes given: torch's reader would otherwise
    inflate records to whatever size the archive declares."""
    try:
        infos = zipfile.ZipFile(io.BytesIO(raw)).infolist()
    except (zipfile.BadZipFile, ValueError, EOFError):
        raise error(f"{path}: not a torch archive (the zip format torch.save writes)") from None
    if len(infos) > max_records:
        raise error(f"{path}: {len(infos)} records in its torch archive; at most {max_records} are allowed")
    if any(i.compress_type != zipfile.ZIP_STORED for i in infos) or sum(i.file_size for i in infos) > len(raw):
        raise error(f"{path}: its torch archive has compressed or oversized records; torch.save stores every "
                    "record uncompressed")


def read_policy_weights(path: str | Path) -> dict[str, torch.Tensor]:
    """The state dict in a stable-baselines3 policy zip, read without unpickling anything but tensors: only the
    ``policy.pth`` entry, sizes checked from the zip's directory first, ``torch.load(weights_only=True)``, every
    value a finite floating tensor. :class:`PolicyError` naming the file otherwise."""
    path = Path(path)
    try:
        with zipfile.ZipFile(path) as z:
            entries = z.infolist()
            if len(entries) > MAX_POLICY_ZIP_ENTRIES:
                raise _refuse(path, f"{len(entries)} zip entries; at most MAX_POLICY_ZIP_ENTRIES = "
                                    f"{MAX_POLICY_ZIP_ENTRIES} are allowed")
            info = next((e for e in entries if e.filename == WEIGHTS_ENTRY), None)
            if info is None:
                raise _refuse(path, f"no {WEIGHTS_ENTRY} entry: not a stable-baselines3 policy zip")
            if info.file_size > MAX_POLICY_WEIGHTS_BYTES:
                raise _refuse(path, f"{WEIGHTS_ENTRY} of {info.file_size} bytes; at most MAX_POLICY_WEIGHTS_BYTES = "
                                    f"{MAX_POLICY_WEIGHTS_BYTES} are allowed")
            raw = z.read(info)  # zipfile stops at the declared size (and checks the CRC)
    except PolicyError:
        raise
    except (zipfile.BadZipFile, OSError, EOFError, ValueError, zlib.error, NotImplementedError, RuntimeError) as exc:
        raise _refuse(path, f"not a readable policy zip ({type(exc).__name__}: {exc})") from None
    check_torch_archive(raw, f"{path}: {WEIGHTS_ENTRY}", PolicyError, MAX_TORCH_RECORDS)
    try:
        state = torch.load(io.BytesIO(raw), map_location="cpu", weights_only=True)
    except Exception as exc:
        text = str(exc).splitlines()[-1] if str(exc) else ""
        raise _refuse(path, f"{WEIGHTS_ENTRY} holds more than tensors and cannot be loaded without running code "
                            f"from the file ({type(exc).__name__}: {text[:300]}); re-train the policy with "
                            "`gendex train`") from None
    if not isinstance(state, dict) or not all(isinstance(k, str) and isinstance(v, torch.Tensor)
                                              for k, v in state.items()):
        raise _refuse(path, f"{WEIGHTS_ENTRY} must hold a mapping of names to tensors")
    check_tensor_sizes(state.items(), f"{path}: {WEIGHTS_ENTRY}", PolicyError, MAX_POLICY_WEIGHTS_BYTES)
    for k, v in state.items():
        if not v.is_floating_point() or not bool(torch.isfinite(v).all()):
            raise _refuse(path, f"weight {k!r} must be finite floating-point numbers")
    return state


def build_policy_network(arch: dict, state: dict[str, torch.Tensor], path: str | Path = "<policy>"):
    """A stable-baselines3 ``ActorCriticPolicy`` of architecture ``arch`` (checked and bounded) with the weights
    ``state`` loaded strictly (every name and shape must match); :class:`PolicyError` otherwise."""
    import gymnasium as gym
    from stable_baselines3.common.policies import ActorCriticPolicy

    arch = _check_architecture(arch, path)
    obs_space = gym.spaces.Box(-np.inf, np.inf, (arch["obs_dim"],), np.float32)
    action_space = gym.spaces.Box(-1.0, 1.0, (arch["action_dim"],), np.float32)
    net = ActorCriticPolicy(obs_space, action_space, lambda _: 0.0, net_arch=list(arch["net_arch"]),
                            activation_fn=ACTIVATIONS[arch["activation"]])
    try:
        net.load_state_dict(state, strict=True)
    except RuntimeError as exc:
        raise _refuse(path, f"its weights do not fit the recorded architecture {arch} ({exc})") from None
    net.set_training_mode(False)
    return net


def load_policy_network(files: PolicyFiles) -> tuple[object, dict]:
    """(network, record) of a trained policy, loaded safely (module doc)."""
    meta = read_policy_record(files.record)
    arch = policy_architecture(meta)
    if isinstance(arch, dict) and arch.get("obs_dim") != len(meta["obs_norm"]["mean"]):
        raise _refuse(files.record, f"architecture obs_dim {arch.get('obs_dim')!r} differs from the "
                                    f"{len(meta['obs_norm']['mean'])} values of obs_norm")
    return build_policy_network(arch, read_policy_weights(files.model), files.model), meta


@dataclass
class StagePolicy:
    """A trained PPO policy of one stage, with what it needs to run on another env of the task."""

    stage: str
    control_joint: str
    judge: Judge
    """The stage's judge: its reward module's extras feed the observation; it tells when the stage is done."""
    model: object
    """Anything with stable-baselines3's ``predict(obs, deterministic)``: the policy network
    (:func:`load_policy_network`), or the PPO being trained."""
    obs_mean: np.ndarray
    obs_var: np.ndarray
    clip_obs: float
    meta: dict
    hold_steps: int = 1
    """Consecutive steps the stage's success must hold before its env counts it (the task's ``hold_steps`` when the
    stage is judged by the task's conditions, as :meth:`~gendex_envs.task_env.TaskEnv.evaluate` counts it; else 1):
    the policy was trained and evaluated acting through them, so it runs through them."""
    _joints: tuple | None = field(default=None, init=False, repr=False)
    """(controller, joint indices, per-joint delta bounds), computed once per controller."""

    @classmethod
    def load(cls, version: TaskVersion, files: PolicyFiles) -> StagePolicy:
        """Load a trained policy of one of ``version``'s stages (``files``: its model and record, from the version
        or from a training run of it); :class:`StageError` when a file is missing."""
        if not files.model.is_file() or not files.record.is_file():
            raise StageError(f"no trained policy for stage {files.stage!r}: need {files.model} and {files.record} "
                             "(`gendex train` writes both)")
        model, meta = load_policy_network(files)
        norm = meta["obs_norm"]
        judge = version.judge(None if files.stage == WHOLE_TASK else files.stage)
        return cls(stage=files.stage, control_joint=meta["control_joint"], judge=judge,
                   model=model, obs_mean=np.asarray(norm["mean"], dtype=np.float32),
                   obs_var=np.asarray(norm["var"], dtype=np.float32), clip_obs=float(norm["clip"]), meta=meta,
                   hold_steps=success_hold_steps(version, files.stage))

    def normalize(self, obs: np.ndarray) -> np.ndarray:
        """Raw flat observation(s) -> what the network takes (the training run's running mean and variance)."""
        if np.shape(obs)[-1] != self.obs_mean.shape[0]:
            raise PolicyError(f"stage {self.stage!r}: observation has {np.shape(obs)[-1]} values, the policy was "
                              f"trained on {self.obs_mean.shape[0]} (different task version or reward module?)")
        return np.clip((obs - self.obs_mean) / np.sqrt(self.obs_var + 1e-8), -self.clip_obs, self.clip_obs)

    def predict(self, obs: np.ndarray, deterministic: bool = True) -> np.ndarray:
        """Normalized action(s) in [-1, 1] for raw observation(s) of the stage's own env."""
        action, _ = self.model.predict(self.normalize(np.asarray(obs, dtype=np.float32)), deterministic=deterministic)
        return np.clip(np.asarray(action, dtype=np.float32), -1.0, 1.0)

    def act(self, env, info: dict | None = None, deterministic: bool = True) -> np.ndarray:
        """[N, F] normalized deltas in [-1, 1] for the stage's free joints (``info``: the stage judge's
        ``evaluate`` of the current state, when the caller has it)."""
        obs = stage_observation(env, self.judge, info).cpu().numpy()
        return self.predict(obs, deterministic).reshape(env.unwrapped.num_envs, -1)

    def targets(self, env, action: np.ndarray) -> torch.Tensor:
        """[N, J] absolute targets of every controller joint after applying ``action`` (the stage env's rule:
        free joints move by ``action`` × the per-step delta bound from their current target, clipped to the joint
        limits; coupled distal joints copy their leader)."""
        ctrl = env.unwrapped.agent.controller
        if self._joints is None or self._joints[0] is not ctrl:
            free = free_joints(self.control_joint)
            self._joints = (ctrl, ctrl.joint_indices(free),
                            torch.tensor(delta_limits(free), dtype=torch.float32, device=ctrl.device))
        _, idx, bound = self._joints
        if action.shape[-1] != len(idx):
            raise PolicyError(f"stage {self.stage!r}: policy gives {action.shape[-1]} actions, control_joint "
                              f"{self.control_joint!r} has {len(idx)} free joints")
        return ctrl.moved_targets(idx, torch.as_tensor(action, device=ctrl.device) * bound)
