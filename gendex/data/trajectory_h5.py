"""ManiSkill-style trajectory files (``<name>.h5`` + ``<name>.json``) for GenDex episodes, and their exact replay.

Layout (as ManiSkill's ``RecordEpisode`` writes it, see ``mani_skill/utils/wrappers/record.py``): one HDF5 group
``traj_<episode_id>`` per episode holding ``actions`` [T, A] float32, ``terminated`` / ``truncated`` / ``success`` /
``fail`` [T] bool, ``rewards`` [T] float32, ``env_states`` [T + 1, E] float32 and ``obs`` [T + 1, S] float32, all
gzip-compressed. Two deliberate differences: ``env_states`` is the *flat* ``env.get_state()`` vector (ManiSkill nests
it as a group mirroring ``get_state_dict()``; ``set_state`` takes the flat form), and ``obs`` is the robot state
(joint positions then velocities), not the env observation. ``terminated = success | fail`` and ``truncated`` is set
from step ``max_episode_steps`` on, as ManiSkill's step and time limit compute them.

The JSON holds ``env_info`` (``env_id``, ``max_episode_steps``, ``env_kwargs``: ``gym.make(env_id, **env_kwargs)``
rebuilds the env) and ``episodes``: ``episode_id``, ``episode_seed``, ``reset_kwargs``, ``control_mode``,
``elapsed_steps``, ``success``, ``fail`` and ``info`` (task id, instruction, ``control_joint``, fps, success, fail and
the episode's own ``info``).

Crash safety: each episode opens the HDF5 file, writes its group, flushes and closes it; only then is the JSON
rewritten (temp file + rename). The JSON is therefore the list of complete episodes: on open, ``traj_*`` groups it
does not list (left by a killed run) are deleted. One writer per file at a time.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import h5py
import numpy as np

from gendex.data.episode import Episode, EpisodeError
from gendex.data.rollout import ReplayError, ReplayResult, replay_rollout
from gendex_envs.atomic_io import write_text

__all__ = ["ReplayError", "ReplayResult", "TrajectoryFileError", "TrajectoryWriter", "load_trajectory_json",
           "replay_episode", "replay_file", "trajectory_paths"]

log = logging.getLogger(__name__)

_COMPRESSION = dict(compression="gzip", compression_opts=4)


class TrajectoryFileError(EpisodeError):
    """A trajectory file pair is missing, malformed, inconsistent (HDF5 vs JSON) or belongs to another env."""


def trajectory_paths(path: Path | str) -> tuple[Path, Path]:
    """(``.h5``, ``.json``) paths of a trajectory file; ``path`` may name either or neither suffix."""
    path = Path(path)
    base = path.with_suffix("") if path.suffix in (".h5", ".json") else path
    return base.with_name(base.name + ".h5"), base.with_name(base.name + ".json")


def _json_default(x):
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, Path):
        return str(x)
    raise TypeError(f"{type(x).__name__} is not JSON serializable")


def _to_json(data, what: str) -> str:
    try:
        return json.dumps(data, indent=2, default=_json_default)
    except (TypeError, ValueError) as e:
        raise EpisodeError(f"{what} cannot be written as JSON: {e}") from None


def load_trajectory_json(path: Path | str) -> dict:
    """The JSON of a trajectory file, checked for ``env_info`` and an ``episodes`` list with ids."""
    _, json_path = trajectory_paths(path)
    try:
        data = json.loads(json_path.read_text())
    except FileNotFoundError:
        raise TrajectoryFileError(f"{json_path} does not exist") from None
    except json.JSONDecodeError as e:
        raise TrajectoryFileError(f"{json_path} is not valid JSON: {e}") from None
    info = data.get("env_info") if isinstance(data, dict) else None
    episodes = data.get("episodes") if isinstance(data, dict) else None
    if not isinstance(info, dict) or "env_id" not in info or not isinstance(episodes, list):
        raise TrajectoryFileError(f"{json_path} needs env_info{{env_id, env_kwargs, ...}} and an episodes list")
    for i, ep in enumerate(episodes):
        if not isinstance(ep, dict) or not isinstance(ep.get("episode_id"), int):
            raise TrajectoryFileError(f"{json_path}: episodes[{i}] has no integer episode_id")
    return data


class TrajectoryWriter:
    """Append episodes to ``<path>.h5`` / ``<path>.json``; reopening an existing pair continues it."""

    def __init__(self, path: Path | str, *, env_id: str, env_kwargs: dict, max_episode_steps: int,
                 source_type: str | None = None):
        self.h5_path, self.json_path = trajectory_paths(path)
        if max_episode_steps < 1:
            raise EpisodeError(f"max_episode_steps={max_episode_steps} must be >= 1")
        env_info = json.loads(_to_json(dict(env_id=env_id, max_episode_steps=int(max_episode_steps),
                                            env_kwargs=dict(env_kwargs)), "env_info"))
        self.env_id, self.env_kwargs, self.max_episode_steps = env_id, env_info["env_kwargs"], int(max_episode_steps)
        if self.json_path.exists():
            self._json = load_trajectory_json(self.json_path)
            if self._json["env_info"] != env_info:
                raise TrajectoryFileError(f"{self.json_path} records env_info {self._json['env_info']}, "
                                          f"not {env_info}; write to another file")
        else:
            self._json = dict(env_info=env_info, episodes=[])
            if source_type is not None:
                self._json["source_type"] = source_type
        self.h5_path.parent.mkdir(parents=True, exist_ok=True)
        self._dims = self._clean()
        ids = self.episode_ids
        self._next_id = max(ids) + 1 if ids else 0
        self._write_json()
        self._closed = False

    # ------------------------------------------------------------------ file state
    @property
    def episode_ids(self) -> list[int]:
        """Ids of the complete episodes in the file, in writing order."""
        return [e["episode_id"] for e in self._json["episodes"]]

    def __len__(self) -> int:
        return len(self._json["episodes"])

    def _clean(self) -> dict[str, int] | None:
        """Delete groups the JSON does not list; check the listed ones exist; return the file's per-row sizes."""
        listed = {f"traj_{i}" for i in self.episode_ids}
        with h5py.File(self.h5_path, "a") as f:
            for name in sorted(set(f.keys()) - listed):
                if name.startswith("traj_"):
                    log.warning("%s: deleting %s, which %s does not list (an interrupted write)",
                                self.h5_path, name, self.json_path.name)
                    del f[name]
            missing = sorted(listed - set(f.keys()))
            if missing:
                raise TrajectoryFileError(f"{self.json_path} lists {missing}, which {self.h5_path} lacks")
            if not listed:
                return None
            g = f[f"traj_{self.episode_ids[0]}"]
            return {k: int(g[k].shape[-1]) for k in ("actions", "obs", "env_states")}

    def _write_json(self):
        write_text(self.json_path, _to_json(self._json, str(self.json_path)), fsync=True)

    # ------------------------------------------------------------------ writing
    def _check(self, ep: Episode) -> dict[str, np.ndarray]:
        where = f"episode of {ep.task_id} (seed {ep.seed})"
        if ep.task_id != self.env_id:
            raise EpisodeError(f"{where}: this file records {self.env_id}")
        mode = self.env_kwargs.get("control_mode")
        if mode is not None and ep.control_mode != mode:
            raise EpisodeError(f"{where}: control_mode {ep.control_mode!r}, the file's env uses {mode!r}")
        seed = ep.reset_kwargs.get("seed", ep.seed)
        if seed != ep.seed:
            raise EpisodeError(f"{where}: reset_kwargs seed {seed} differs from the episode seed")
        arrays = {"actions": ep.action, "obs": ep.state, "env_states": ep.env_states, "rewards": ep.reward}
        out = {}
        for key, value in arrays.items():
            a = np.asarray(value)
            ndim = 1 if key == "rewards" else 2
            if a.ndim != ndim or not np.issubdtype(a.dtype, np.number):
                raise EpisodeError(f"{where}: {key} must be a {ndim}-D numeric array, got {a.dtype} {list(a.shape)}")
            if not np.isfinite(a).all():
                raise EpisodeError(f"{where}: {key} holds NaN or inf")
            if self._dims is not None and key in self._dims and a.shape[-1] != self._dims[key]:
                raise EpisodeError(f"{where}: {key} rows have {a.shape[-1]} values; the file's episodes have "
                                   f"{self._dims[key]}")
            out[key] = a.astype(np.float32)
        for key, value in (("success", ep.success), ("fail", ep.fail)):
            a = np.asarray(value)
            if a.ndim != 1 or a.dtype != np.bool_:
                raise EpisodeError(f"{where}: {key} must be a 1-D bool array, got {a.dtype} {list(a.shape)}")
            out[key] = a
        steps = np.arange(1, ep.length + 1)
        out["terminated"] = out["success"] | out["fail"]
        out["truncated"] = steps >= self.max_episode_steps
        return out

    def add_episode(self, ep: Episode) -> int:
        """Write ``ep`` as ``traj_<id>`` and list it in the JSON; returns its episode id."""
        if self._closed:
            raise EpisodeError(f"writer of {self.h5_path} is closed")
        arrays = self._check(ep)
        episode_id = self._next_id
        info = {**ep.info, "task_id": ep.task_id, "instruction": ep.instruction, "control_joint": ep.control_joint,
                "fps": int(ep.fps), "success": ep.succeeded, "fail": bool(ep.fail[-1])}
        record = dict(episode_id=episode_id, episode_seed=int(ep.seed),
                      reset_kwargs={**ep.reset_kwargs, "seed": int(ep.seed)}, control_mode=ep.control_mode,
                      elapsed_steps=ep.length, success=ep.succeeded, fail=bool(ep.fail[-1]), info=info)
        record = json.loads(_to_json(record, f"episode {episode_id} (seed {ep.seed}) info"))
        name = f"traj_{episode_id}"
        order = ("actions", "terminated", "truncated", "success", "fail", "rewards", "env_states", "obs")
        with h5py.File(self.h5_path, "a") as f:
            if name in f:
                del f[name]
            group = f.create_group(name, track_order=True)
            for key in order:
                group.create_dataset(key, data=arrays[key], **_COMPRESSION)
            f.flush()
        self._json["episodes"].append(record)
        self._write_json()
        self._next_id += 1
        if self._dims is None:
            self._dims = {k: int(arrays[k].shape[-1]) for k in ("actions", "obs", "env_states")}
        return episode_id

    def close(self):
        self._closed = True

    def __enter__(self) -> TrajectoryWriter:
        return self

    def __exit__(self, *exc):
        self.close()


# ---------------------------------------------------------------------- replay
def _read_traj(h5: h5py.File, meta: dict, h5_path: Path) -> dict[str, np.ndarray]:
    name = f"traj_{meta['episode_id']}"
    if name not in h5:
        raise TrajectoryFileError(f"{h5_path} has no group {name}")
    g = h5[name]
    missing = [k for k in ("actions", "env_states", "success") if k not in g]
    if missing:
        raise TrajectoryFileError(f"{h5_path}:{name} lacks datasets {missing}")
    data = {k: g[k][()] for k in ("actions", "env_states", "success")}
    t = meta.get("elapsed_steps")
    a, s, ok = data["actions"], data["env_states"], data["success"]
    if a.ndim != 2 or len(a) != t or s.ndim != 2 or len(s) != t + 1 or ok.shape != (t,):
        raise TrajectoryFileError(f"{h5_path}:{name}: elapsed_steps={t} but actions {list(a.shape)}, env_states "
                                  f"{list(s.shape)}, success {list(ok.shape)} (expected [T, A], [T+1, E], [T])")
    return data


def _replay(env, meta: dict, data: dict[str, np.ndarray], use_env_states: bool, init_tol: float) -> ReplayResult:
    eid, mode = meta["episode_id"], env.unwrapped.control_mode
    if meta.get("control_mode") not in (None, mode):
        raise ReplayError(f"episode {eid} was recorded in {meta['control_mode']}, the env runs {mode}")
    return replay_rollout(env, data["actions"], data["env_states"], data["success"],
                          reset_kwargs={**meta.get("reset_kwargs", {}), "seed": meta["episode_seed"]},
                          episode_id=eid, use_env_states=use_env_states, init_tol=init_tol)


def _make_env(info: dict):
    import gymnasium as gym

    import gendex_envs  # noqa: F401  (registers the GenDex tasks)

    return gym.make(info["env_id"], **info.get("env_kwargs", {}))


def _replay_many(h5_path, episode_ids: list[int] | None, use_env_states: bool, init_tol: float) -> list[ReplayResult]:
    h5_path, _ = trajectory_paths(h5_path)
    data_json = load_trajectory_json(h5_path)
    by_id = {e["episode_id"]: e for e in data_json["episodes"]}
    ids = list(by_id) if episode_ids is None else episode_ids
    unknown = [i for i in ids if i not in by_id]
    if unknown:
        raise TrajectoryFileError(f"{h5_path}: no episodes {unknown}; episodes: {sorted(by_id)}")
    if not h5_path.exists():
        raise TrajectoryFileError(f"{h5_path} does not exist")
    with h5py.File(h5_path, "r") as h5:  # read (and check) every trajectory before paying for an env
        trajs = [_read_traj(h5, by_id[i], h5_path) for i in ids]
    env = _make_env(data_json["env_info"])
    try:
        return [_replay(env, by_id[i], data, use_env_states, init_tol) for i, data in zip(ids, trajs, strict=True)]
    finally:
        env.close()


def replay_episode(h5_path: Path | str, episode_id: int, *, use_env_states: bool = False,
                   init_tol: float = 1e-4) -> ReplayResult:
    """Rebuild the env from the JSON, reset with the recorded seed, check the reset state against the recorded one
    (:class:`ReplayError` beyond ``init_tol``), step the recorded actions and compare the final object positions and
    success flags (see :func:`~gendex.data.rollout.replay_rollout`). A plain replay on the same build is exact;
    ``use_env_states`` restores the recorded state after every step (ManiSkill's ``--use-env-states``), so errors are
    one-step errors, but not zero: setting a state drops PhysX's contact caches."""
    return _replay_many(h5_path, [episode_id], use_env_states, init_tol)[0]


def replay_file(h5_path: Path | str, *, use_env_states: bool = False, init_tol: float = 1e-4) -> list[ReplayResult]:
    """:func:`replay_episode` for every episode of the file (one env for all)."""
    return _replay_many(h5_path, None, use_env_states, init_tol)
