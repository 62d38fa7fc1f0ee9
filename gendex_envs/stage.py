"""A task's sub-stage as an environment of its own: where its reward, start states and trained policy live.

``TaskEnv(task_dir=..., stage="grasp_bottle")`` (or ``gym.make(env_id, stage=1)``) is the stage's env: actions drive
the stage's ``control_joint`` group, the reward module is ``stage_rewards/<stage>.py`` when the task has one (else the
task's ``reward.py``), episodes last the stage's ``horizon``, and every reset starts from one of the states saved at
the success of the previous stage (:class:`StartStates`). Files of one task version::

    generated_tasks/<Name>/v<N>/
        stage_rewards/<stage>.py        reward module of the stage (optional; default: reward.py)
        start_states/<stage>.npz        states the stage starts from (stages after the first)
        policies/<stage>.zip            trained PPO policy, used by the stage executor when present
        policies/<stage>.json           what trained it: preset, steps, seed, evaluation, command
        policies/<stage>/progress.csv   training curve (checkpoints/ beside it, not committed)
"""

from __future__ import annotations

import json
import logging
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gendex_envs.atomic_io import atomic_path
from gendex_envs.errors import StageError, suggest
from gendex_envs.spec import StageSpec, TaskSpec

log = logging.getLogger(__name__)

STAGE_REWARDS_DIR = "stage_rewards"
START_STATES_DIR = "start_states"
POLICIES_DIR = "policies"


def resolve_stage(spec: TaskSpec, stage: str | int) -> tuple[int, StageSpec]:
    """(index, spec) of ``stage`` given by name or index; :class:`StageError` naming the stages otherwise."""
    names = [s.name for s in spec.stages]
    if isinstance(stage, (int, np.integer)) and not isinstance(stage, bool):
        if not 0 <= int(stage) < len(names):
            raise StageError(f"task {spec.name!r} has no stage {int(stage)}; stages 0..{len(names) - 1}: {names}")
        return int(stage), spec.stages[int(stage)]
    if isinstance(stage, str) and stage.isdigit():
        return resolve_stage(spec, int(stage))
    if stage not in names:
        raise StageError(f"task {spec.name!r} has no stage {stage!r}; stages: {names}.{suggest(str(stage), names)}")
    return names.index(stage), spec.stages[names.index(stage)]


def stage_reward_path(task_dir: str | Path, stage: str) -> Path:
    """The stage's reward module: ``stage_rewards/<stage>.py`` if the task has one, else ``reward.py``."""
    own = Path(task_dir) / STAGE_REWARDS_DIR / f"{stage}.py"
    return own if own.is_file() else Path(task_dir) / "reward.py"


def start_states_path(task_dir: str | Path, stage: str) -> Path:
    return Path(task_dir) / START_STATES_DIR / f"{stage}.npz"


def policy_path(task_dir: str | Path, stage: str) -> Path:
    return Path(task_dir) / POLICIES_DIR / f"{stage}.zip"


@dataclass(frozen=True)
class StartStates:
    """States a stage starts from, captured when the previous stage succeeded (one row per captured episode).

    ``state`` rows are :meth:`TaskEnv.get_state` vectors (simulation state, then every joint's controller target),
    so they restore into an env of any ``control_joint`` mode. ``obj_reset_pos`` / ``obj_reset_quat`` keep each
    object's pose at the start of the *task* episode, so ``env.obj_height`` still measures from the table.
    """

    stage: str
    state: np.ndarray
    """[M, D] float32."""
    obj_reset_pos: dict[str, np.ndarray] = field(default_factory=dict)
    """object name -> [M, 3]."""
    obj_reset_quat: dict[str, np.ndarray] = field(default_factory=dict)
    """object name -> [M, 4] (wxyz)."""
    source: str = ""
    """How the states were made (e.g. 'executor', 'policy:reach_apple')."""

    def __post_init__(self):
        if self.state.ndim != 2 or len(self.state) == 0:
            raise StageError(f"start states of stage {self.stage!r} must be a non-empty [M, D] array, "
                             f"got shape {self.state.shape}")
        m = len(self.state)
        for kind, table, width in (("obj_reset_pos", self.obj_reset_pos, 3),
                                   ("obj_reset_quat", self.obj_reset_quat, 4)):
            for name, value in table.items():
                if value.shape != (m, width):
                    raise StageError(f"start states of stage {self.stage!r}: {kind}[{name!r}] has shape {value.shape}, "
                                     f"expected ({m}, {width})")

    def __len__(self) -> int:
        return len(self.state)

    @classmethod
    def capture(cls, env, stage: str, source: str) -> StartStates:
        """The current state of ``env`` (a :class:`~gendex_envs.task_env.TaskEnv` or a wrapper of one), one row
        per sub-scene, as start states of ``stage``."""
        u = env.unwrapped
        return cls(stage=stage, source=source, state=u.get_state().cpu().numpy().astype(np.float32),
                   obj_reset_pos={n: u.init_obj_pos(n).cpu().numpy() for n in u.objects},
                   obj_reset_quat={n: u.init_obj_quat(n).cpu().numpy() for n in u.objects})

    def save(self, path: str | Path) -> Path:
        """Write atomically (temp file in the same folder, then rename)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        arrays = {"state": self.state.astype(np.float32), "meta": np.array(json.dumps(
            {"stage": self.stage, "source": self.source, "objects": sorted(self.obj_reset_pos)}))}
        arrays.update({f"pos/{k}": v.astype(np.float32) for k, v in self.obj_reset_pos.items()})
        arrays.update({f"quat/{k}": v.astype(np.float32) for k, v in self.obj_reset_quat.items()})
        with atomic_path(path) as tmp, tmp.open("wb") as f:
            np.savez_compressed(f, **arrays)
        return path

    @classmethod
    def load(cls, path: str | Path) -> StartStates:
        path = Path(path)
        if not path.is_file():
            raise StageError(f"no start states at {path}")
        try:
            with np.load(path, allow_pickle=False) as z:
                meta = json.loads(str(z["meta"]))
                return cls(stage=meta["stage"], source=meta.get("source", ""), state=z["state"],
                           obj_reset_pos={k: z[f"pos/{k}"] for k in meta["objects"]},
                           obj_reset_quat={k: z[f"quat/{k}"] for k in meta["objects"] if f"quat/{k}" in z})
        except (KeyError, ValueError, OSError) as e:
            raise StageError(f"{path} is not a GenDex start-state file: {type(e).__name__}: {e}") from e

    @classmethod
    def concat(cls, parts: list[StartStates]) -> StartStates:
        if not parts:
            raise StageError("no start states to join")
        names = sorted(parts[0].obj_reset_pos)
        return cls(stage=parts[0].stage, source=parts[0].source,
                   state=np.concatenate([p.state for p in parts]),
                   obj_reset_pos={k: np.concatenate([p.obj_reset_pos[k] for p in parts]) for k in names},
                   obj_reset_quat={k: np.concatenate([p.obj_reset_quat[k] for p in parts]) for k in names
                                   if all(k in p.obj_reset_quat for p in parts)})
