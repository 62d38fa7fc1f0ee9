"""Collect successful episodes of a task with a solver and export them (LeRobot v3.0 and/or HDF5 + JSON).

Only successful episodes are kept. Attempt ``k`` resets with seed ``base_seed + k``; GenDex envs are deterministic,
so a collection is reproducible and resumable:

* each exporter appends an episode atomically (see :mod:`~gendex.data.lerobot_v3` and
  :mod:`~gendex.data.trajectory_h5`), then progress (attempts, env steps, kept seeds) is committed to
  ``collect_state.json``;
* on restart the collector continues after the last committed attempt. If it was killed after some exporter had
  taken the next successful episode but before the commit, that attempt is re-run (same seed, same episode) and
  given to the exporters that lack it, so every format ends with the same episodes.
"""

from __future__ import annotations

import functools
import json
import logging
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import gymnasium as gym
import numpy as np

from gendex.data.episode import Episode, EpisodeError
from gendex.data.rollout import EpisodeRecorder, env_info
from gendex.fanout import Backend, ordered_map
from gendex.solve.attempt import run_attempt
from gendex.solve.failure import Failure
from gendex_envs import observation
from gendex_envs.atomic_io import write_json
from gendex_envs.registry import HISTORY_FREE
from gendex_envs.video import DEFAULT_CODEC

if TYPE_CHECKING:  # pragma: no cover
    from gendex.solve import Solver

log = logging.getLogger(__name__)

STATE_FILE = "collect_state.json"
FORMATS = ("lerobot", "h5")


@dataclass(frozen=True)
class CollectConfig:
    task_id: str
    num_success: int
    out: Path
    formats: tuple[str, ...] = ("lerobot",)
    cameras: tuple[str, ...] = ()
    seed: int = 0
    max_attempts: int | None = None
    """Stop after this many attempts even if ``num_success`` is not reached (default: 20 x num_success)."""
    control_mode: str = "pd_joint_pos"
    """Action space of the solver's actions (``gendex.solve.SOLVER_ENV_KWARGS``); recorded with the data."""
    control_joint: str = "both"
    resolution: int = 128
    """Camera images are ``resolution`` x ``resolution`` (the env's ``sensor_resolution``)."""
    video_codec: str | None = DEFAULT_CODEC
    """Camera images as MP4 videos with this encoder (LeRobot v3.0's ``videos/``), or None: PNG in the parquet."""
    conventions: int = 1
    """The LeRobot dataset's stats (:class:`~gendex.data.lerobot_v3.LeRobotV3Writer`): 1 as the published datasets,
    2 lerobot 0.4's (with the quantiles q01 ... q99), 3 as 2 with the dataset's quantiles over all its frames."""

    def env_kwargs(self) -> dict:
        """The exact ``gym.make`` keyword arguments of the collection's env (recorded in the dataset)."""
        kwargs = {"control_mode": self.control_mode, "control_joint": self.control_joint,
                  "obs_mode": "rgb" if self.cameras else "state", **HISTORY_FREE}
        if self.cameras:  # only the recorded cameras render (each declared one renders at every step)
            kwargs["sensor_resolution"] = self.resolution
            kwargs["sensors"] = list(self.cameras)
        return kwargs


@dataclass
class CollectState:
    """Committed progress of a collection."""

    task_id: str
    seed: int
    attempts: int = 0
    env_steps: int = 0
    kept_seeds: list[int] = field(default_factory=list)
    seconds: float = 0.0
    failures: dict[str, int] = field(default_factory=dict)
    """Failed attempts per ``stage/skill/cause`` (:class:`~gendex.solve.failure.Failure`)."""

    @property
    def successes(self) -> int:
        return len(self.kept_seeds)

    @property
    def env_steps_per_success(self) -> float:
        return self.env_steps / self.successes if self.successes else float("inf")


def _load_state(cfg: CollectConfig) -> CollectState:
    path = cfg.out / STATE_FILE
    if not path.is_file():
        return CollectState(task_id=cfg.task_id, seed=cfg.seed)
    raw = json.loads(path.read_text())
    state = CollectState(**{k: v for k, v in raw.items() if k in CollectState.__dataclass_fields__})
    if (state.task_id, state.seed) != (cfg.task_id, cfg.seed):
        raise EpisodeError(f"{path} belongs to a collection of {state.task_id} with seed {state.seed}; asked for "
                           f"{cfg.task_id} with seed {cfg.seed} (use another --out or the same task and seed)")
    return state


def _open_exporters(cfg: CollectConfig, env: gym.Env) -> dict[str, object]:
    from gendex.data.lerobot_v3 import LeRobotV3Writer
    from gendex.data.trajectory_h5 import TrajectoryWriter

    unknown = [f for f in cfg.formats if f not in FORMATS]
    if unknown:
        raise EpisodeError(f"unknown formats {unknown}; allowed: {list(FORMATS)}")
    u = env.unwrapped
    writers: dict[str, object] = {}
    if "lerobot" in cfg.formats:
        action_names = list(u.agent.controller.free_joint_names)
        res = u.sensor_resolution
        writers["lerobot"] = LeRobotV3Writer(
            cfg.out / "lerobot", fps=int(u.control_freq), robot_type="ur10e_shadowhand",
            state_names=observation.robot_state_names(env), action_names=action_names,
            environment_state_names=observation.environment_state_names(env),
            cameras={c: (res, res) for c in cfg.cameras} or None, video_codec=cfg.video_codec,
            conventions=cfg.conventions)
    if "h5" in cfg.formats:
        writers["h5"] = TrajectoryWriter(cfg.out / "trajectories", **env_info(env))
    return writers


@dataclass
class AttemptResult:
    """What one attempt produced (picklable, so worker processes can return it)."""

    seed: int
    episode: Episode | None
    """The recorded episode when it succeeded, else None."""
    steps: int
    seconds: float
    failure: Failure | None = None
    """Why it failed (None when it succeeded)."""


def _make_env(cfg: CollectConfig) -> gym.Env:
    return gym.make(cfg.task_id, **cfg.env_kwargs())


class _Attempter:
    """Runs attempts by seed with its own env and solver (in this process or in a worker)."""

    def __init__(self, cfg: CollectConfig, make_solver: Callable[[], Solver]):
        self.cfg = cfg
        self.env = _make_env(cfg)
        self.recorder = EpisodeRecorder(self.env)
        self.solver = make_solver()

    def __call__(self, seed: int) -> AttemptResult:
        t0 = time.perf_counter()
        episode, images, failure = _attempt(self.env, self.recorder, self.solver, seed, self.cfg.cameras)
        kept = None
        if episode is not None and episode.succeeded:
            episode.images.update(images)
            episode.info.update(solver=self.solver.name)
            kept, failure = episode, None
        elif failure is None:  # recorded, but the success came too late or not at all
            failure = Failure("target_not_reached", detail="the episode ended without the task's success")
        return AttemptResult(seed, kept, self.recorder.steps, time.perf_counter() - t0, failure)


def attempt_once(cfg: CollectConfig, make_solver: Callable[[], Solver], seed: int
                 ) -> tuple[Episode | None, int, Failure | None]:
    """One attempt exactly as :func:`collect` runs it (its env, recorder and solver, built for this attempt): the
    recorded episode (None when no step was taken), the steps taken, and why it failed (None when it succeeded)."""
    attempter = _Attempter(cfg, make_solver)
    try:
        episode, _images, failure = _attempt(attempter.env, attempter.recorder, attempter.solver, seed, cfg.cameras)
        if failure is None and (episode is None or not episode.succeeded):
            failure = Failure("target_not_reached", detail="the episode ended without the task's success")
        return episode, attempter.recorder.steps, failure
    finally:
        attempter.env.close()


def _make_attempter(cfg: CollectConfig, make_solver: Callable[[], Solver], task_root: str) -> _Attempter:
    """A worker process's attempter (:func:`gendex.fanout.ordered_map`): registers a task registered at run time
    in the parent (e.g. a scratch root) first. A worker started with pinned numerics checks that they took."""
    import gendex_envs  # noqa: F401
    from gendex.data import numerics
    from gendex_envs.registry import register_tasks

    numerics.check()

    if cfg.task_id not in gym.registry:
        register_tasks([Path(task_root)])
    return _Attempter(cfg, make_solver)


def collect(cfg: CollectConfig, make_solver: Callable[[], Solver],
            progress: Callable[[CollectState], None] | None = None, workers: int = 1,
            backend: Backend | None = None) -> CollectState:
    """Run attempts until ``cfg.num_success`` episodes succeeded (or ``max_attempts``); returns the final state.

    Attempts run on ``backend`` (:class:`gendex.fanout.Backend`; default: ``workers`` local processes, or this
    process for one): each worker keeps one env; results are committed in attempt order, so the dataset is the
    same as with one worker, and on Ray a worker killed mid-attempt has its attempts re-run by another.
    """
    from gendex_envs.registry import resolve_task

    if workers < 1:
        raise EpisodeError(f"workers={workers}; allowed: 1 or more")
    backend = backend or Backend.from_options(workers)
    cfg.out.mkdir(parents=True, exist_ok=True)
    state = _load_state(cfg)
    limit = cfg.max_attempts if cfg.max_attempts is not None else 20 * cfg.num_success
    # the exporters need the env's names and shapes; the attempts need an env and a solver only in this process
    local = _Attempter(cfg, make_solver) if backend.kind == "local" else None
    env = local.env if local is not None else _make_env(cfg)
    writers = _open_exporters(cfg, env)
    results = None
    try:
        pending = {name: _exported(w) - state.successes for name, w in writers.items()}
        if any(n < 0 or n > 1 for n in pending.values()):
            counts = {k: _exported(w) for k, w in writers.items()}
            raise EpisodeError(f"{cfg.out}: exported episode counts {counts} do not match the {state.successes} "
                               f"committed in {STATE_FILE}")
        seeds = (cfg.seed + k for k in range(state.attempts, limit))
        if backend.kind == "local":
            results = map(local, seeds)
        else:
            root = str(resolve_task(cfg.task_id).tasks_root)
            results = ordered_map(functools.partial(_make_attempter, cfg, make_solver, root), seeds, backend)
        for result in results if state.successes < cfg.num_success else ():
            if result.episode is not None:
                result.episode.info.update(attempt=state.attempts)
                for name, writer in writers.items():
                    if pending.get(name, 0) > 0:  # this writer already took it before an interruption
                        log.info("attempt %d (seed %d) was already exported to %s", state.attempts, result.seed, name)
                        continue
                    writer.add_episode(result.episode)
                state.kept_seeds.append(result.seed)
            elif any(pending.values()):
                raise EpisodeError(f"attempt {state.attempts} (seed {result.seed}) was exported before an "
                                   "interruption but did not succeed when re-run: the solver or env is not "
                                   "deterministic")
            else:
                failure = result.failure or Failure("target_not_reached")
                state.failures[failure.key] = state.failures.get(failure.key, 0) + 1
                log.info("attempt %d (seed %d) failed: %s", state.attempts, result.seed, failure)
            pending = {}
            state.attempts += 1
            state.env_steps += result.steps
            state.seconds += result.seconds
            write_json(cfg.out / STATE_FILE, asdict(state), indent=1)
            if progress is not None:
                progress(state)
            if state.successes >= cfg.num_success:
                break
    finally:
        if hasattr(results, "close"):
            results.close()  # ends the workers
        for writer in writers.values():
            writer.close()
        env.close()
    return state


def _exported(writer) -> int:
    """Episodes an exporter holds."""
    from gendex.data.lerobot_v3 import LeRobotV3Writer

    return writer.total_episodes if isinstance(writer, LeRobotV3Writer) else len(writer)


def _attempt(env: gym.Env, recorder: EpisodeRecorder, solver: Solver, seed: int, cameras: tuple[str, ...]
             ) -> tuple[Episode | None, dict[str, np.ndarray], Failure | None]:
    """Run one attempt (:func:`gendex.solve.attempt.run_attempt`, recorded); the recorded episode (None if no step
    was taken), camera frames, and why it failed (None when it may have succeeded: the caller checks)."""
    frames: dict[str, list[np.ndarray]] = {c: [] for c in cameras}

    def see(obs) -> None:
        for c in cameras:
            frames[c].append(_image(obs, c))

    failure = run_attempt(env, solver, seed, recorder.hooks(seed, see)).failure
    if recorder.steps == 0:
        return None, {}, failure or Failure("target_not_reached", detail="the solver took no step")
    return recorder.episode(), {c: np.stack(v) for c, v in frames.items()}, failure


def _image(obs, camera: str) -> np.ndarray:
    try:
        return np.asarray(obs["sensor_data"][camera]["rgb"])
    except (KeyError, TypeError) as exc:
        raise EpisodeError(f"camera {camera!r} is not in the observation; cameras: "
                           f"{sorted(obs.get('sensor_data', {})) if isinstance(obs, dict) else []}") from exc


GENDEX_META = "gendex.json"
"""``meta/gendex.json`` of a LeRobot collection: the task id, the exact ``gym.make`` keyword arguments, the solver
and each episode's reset seed (what a learner needs to act in the same env and an evaluation to check that its
seeds are unseen); lerobot ignores it."""


def write_card(cfg: CollectConfig, instruction: str, solver: str, state: CollectState) -> Path:
    """The dataset card of a LeRobot collection (``<out>/lerobot/README.md``: the exact ``gym.make`` call, how
    observations are read, how the episodes were made) and its ``meta/gendex.json``."""
    from gendex.data.lerobot_v3 import write_dataset_card

    root = cfg.out / "lerobot"
    info = json.loads((root / "meta" / "info.json").read_text())
    seeds = f"{cfg.seed}..{cfg.seed + state.attempts - 1}"
    write_json(root / "meta" / GENDEX_META, {"task_id": cfg.task_id, "env_kwargs": cfg.env_kwargs(),
                                             "solver": solver, "episode_seeds": state.kept_seeds}, indent=1)
    return write_dataset_card(root, task_id=cfg.task_id, instruction=instruction,
                              robot="ShadowHand on UR10e (30 joints)", env_kwargs=cfg.env_kwargs(),
                              n_episodes=info["total_episodes"], n_frames=info["total_frames"],
                              how_made=f"gendex collect with solver '{solver}', seeds {seeds}")
