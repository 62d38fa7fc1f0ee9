"""Start states of a stage env: where the previous stage succeeded, saved so the stage can be trained on its own.

A stage after the first starts every episode from one of these states (``TaskEnv(stage=...)``). They are an artifact
of a task version (or of a training run), stored as ``.npz`` with atomic writes; no pickle.
"""

from __future__ import annotations

import json
import logging
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gendex_envs.atomic_io import atomic_path
from gendex_envs.errors import StageError

log = logging.getLogger(__name__)


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
