"""Start states of a stage env: where the previous stage succeeded, saved so the stage can be trained on its own.

A stage after the first starts every episode from one of these states (``TaskEnv(stage=...)``). They are an artifact
of a task version (or of a training run), stored as ``.npz`` with atomic writes; no pickle.

A start-state file may come from an untrusted task folder. :meth:`StartStates.load` refuses, with a
:class:`StageError` naming the limit and its value, before it decompresses anything: more than
``MAX_START_STATE_ENTRIES`` arrays or ``MAX_START_STATE_BYTES`` uncompressed bytes (read from the zip's directory;
``zipfile`` never inflates past the declared size), an array header whose shape, dtype or size disagree with that
entry (only float32/float64 arrays and one short ``meta`` string), more than ``MAX_START_STATE_ROWS`` rows or
``MAX_STATE_WIDTH`` columns. Every :class:`StartStates` (loaded or built) holds only finite values within
``MAX_STATE_ABS``, reset positions within ``MAX_POSITION_M`` and unit reset quaternions: they go straight into the
simulator.
"""

from __future__ import annotations

import json
import logging
import math
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gendex_envs.atomic_io import atomic_path
from gendex_envs.errors import StageError

log = logging.getLogger(__name__)

MAX_START_STATE_BYTES = 64_000_000
"""Uncompressed bytes of every array of a start-state file together. ``gendex train`` saves 64 states of about 130
floats (33 KB); the bound leaves room for 100 000 rows of that width."""
MAX_START_STATE_ENTRIES = 256
"""Arrays in a file: ``state``, ``meta`` and a position and a quaternion per object (at most 64 objects)."""
MAX_START_STATE_ROWS = 100_000
MAX_STATE_WIDTH = 4096
"""Columns of ``state`` (the committed tasks' states have 116 to 129)."""
MAX_META_CHARS = 65_536
"""Characters of the ``meta`` JSON (stage, source and object names: about 100)."""
MAX_STATE_ABS = 10_000.0
"""Largest absolute value in ``state`` (positions in m, velocities in m/s and rad/s, joint positions and targets):
about 100 times the largest value a committed task's state reaches (93 rad/s)."""
MAX_POSITION_M = 100.0
"""Largest absolute coordinate of an object's reset position, in metres (the scenes span about 2 m)."""
QUAT_NORM_TOLERANCE = 1e-3
"""How far a reset quaternion's norm may be from 1."""
_FLOATS = (np.dtype("<f4"), np.dtype("<f8"))


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
        if m > MAX_START_STATE_ROWS or self.state.shape[1] > MAX_STATE_WIDTH:
            raise StageError(f"start states of stage {self.stage!r}: state has shape {self.state.shape}; at most "
                             f"MAX_START_STATE_ROWS = {MAX_START_STATE_ROWS} rows of MAX_STATE_WIDTH = "
                             f"{MAX_STATE_WIDTH} values are allowed")
        for kind, table, width in (("obj_reset_pos", self.obj_reset_pos, 3),
                                   ("obj_reset_quat", self.obj_reset_quat, 4)):
            for name, value in table.items():
                if value.shape != (m, width):
                    raise StageError(f"start states of stage {self.stage!r}: {kind}[{name!r}] has shape {value.shape}, "
                                     f"expected ({m}, {width})")
        self._check_values()

    def _check_values(self) -> None:
        """Finite, bounded numbers only (module doc): they are written into the simulator as they are."""
        where = f"start states of stage {self.stage!r}"
        arrays = [("state", self.state, MAX_STATE_ABS, "MAX_STATE_ABS")]
        arrays += [(f"obj_reset_pos[{k!r}]", v, MAX_POSITION_M, "MAX_POSITION_M")
                   for k, v in self.obj_reset_pos.items()]
        arrays += [(f"obj_reset_quat[{k!r}]", v, 1.0 + QUAT_NORM_TOLERANCE, "unit quaternions")
                   for k, v in self.obj_reset_quat.items()]
        for what, value, bound, name in arrays:
            if value.dtype.kind != "f" or value.dtype.itemsize not in (4, 8):
                raise StageError(f"{where}: {what} has dtype {value.dtype}; only float32 and float64 are allowed")
            if not np.isfinite(value).all():
                raise StageError(f"{where}: {what} holds NaN or infinite values; only finite numbers are allowed")
            if np.abs(value).max(initial=0.0) > bound:
                raise StageError(f"{where}: {what} holds {float(np.abs(value).max()):.3g}; values beyond {name} = "
                                 f"{bound:g} are not allowed")
        for name, quat in self.obj_reset_quat.items():
            norm = np.linalg.norm(quat.astype(np.float64), axis=-1)
            if np.abs(norm - 1.0).max(initial=0.0) > QUAT_NORM_TOLERANCE:
                raise StageError(f"{where}: obj_reset_quat[{name!r}] has a quaternion of norm "
                                 f"{float(norm[np.argmax(np.abs(norm - 1))]):.6g}; norms must lie within "
                                 f"QUAT_NORM_TOLERANCE = {QUAT_NORM_TOLERANCE} of 1")

    def check_fits(self, width: int, objects) -> None:
        """:class:`StageError` unless these states restore into an env whose :meth:`TaskEnv.get_state` rows are
        ``width`` values wide and whose objects are ``objects`` (states of another task or layout)."""
        missing = sorted(set(objects) - set(self.obj_reset_pos))
        if self.state.shape[1] != width or missing:
            raise StageError(f"start states of stage {self.stage!r} ({self.source or 'given'}) do not fit this env: "
                             f"rows of {self.state.shape[1]} values (the env's state has {width})"
                             + (f", no reset poses for {missing}" if missing else ""))

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
        """Read a start-state file, bounded and checked before anything is decompressed (module doc)."""
        path = Path(path)
        if not path.is_file():
            raise StageError(f"no start states at {path}")
        try:
            z = _read_npz(path)
            meta = json.loads(str(z["meta"]))
            objects = meta.get("objects") if isinstance(meta, dict) else None
            if not isinstance(meta.get("stage") if isinstance(meta, dict) else None, str) \
                    or not isinstance(objects, list) or not all(isinstance(k, str) for k in objects):
                raise ValueError("meta must be an object with a string `stage` and a list of `objects` names")
            return cls(stage=meta["stage"], source=str(meta.get("source", "")), state=z["state"],
                       obj_reset_pos={k: z[f"pos/{k}"] for k in meta["objects"]},
                       obj_reset_quat={k: z[f"quat/{k}"] for k in meta["objects"] if f"quat/{k}" in z})
        except StageError as e:
            raise StageError(f"{path}: {e}") from None
        except (KeyError, ValueError, OSError, EOFError, zipfile.BadZipFile, zlib.error, NotImplementedError,
                RuntimeError) as e:  # corrupt deflate data, unknown compression, encrypted entries
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


def _read_npz(path: Path) -> dict[str, np.ndarray]:
    """The arrays of an ``.npz`` file, every bound checked from the zip's directory and each array's header before
    its data is read (module doc); :class:`StageError` naming the limit, ``ValueError`` for a malformed file."""
    fmt = np.lib.format
    out: dict[str, np.ndarray] = {}
    with zipfile.ZipFile(path) as z:
        infos = z.infolist()
        if len(infos) > MAX_START_STATE_ENTRIES:
            raise StageError(f"{len(infos)} arrays; at most MAX_START_STATE_ENTRIES = {MAX_START_STATE_ENTRIES} "
                             "are allowed")
        total = sum(i.file_size for i in infos)
        if total > MAX_START_STATE_BYTES:
            raise StageError(f"{total} bytes uncompressed; at most MAX_START_STATE_BYTES = {MAX_START_STATE_BYTES} "
                             "are allowed")
        for info in infos:
            name = info.filename.removesuffix(".npy")
            if name == info.filename or name in out:
                raise ValueError(f"entry {info.filename[:100]!r} is not a distinct .npy array")
            with z.open(info) as f:
                version = fmt.read_magic(f)
                if version not in ((1, 0), (2, 0)):
                    raise ValueError(f"{name}: .npy format {version} (1.0 and 2.0 are read)")
                read_header = fmt.read_array_header_1_0 if version == (1, 0) else fmt.read_array_header_2_0
                shape, fortran, dtype = read_header(f, max_header_size=10_000)
                if name == "meta":
                    if shape != () or dtype.kind != "U" or dtype.itemsize > 4 * MAX_META_CHARS:
                        raise StageError(f"meta must be one string of at most MAX_META_CHARS = {MAX_META_CHARS} "
                                         f"characters, got {dtype} {shape}")
                elif dtype not in _FLOATS or len(shape) > 2:
                    raise StageError(f"{name} is a {dtype} array of shape {shape}; only float32 or float64 arrays "
                                     "of at most 2 dimensions are allowed")
                nbytes = math.prod(shape) * dtype.itemsize
                if nbytes > info.file_size:
                    raise StageError(f"{name}: its header promises {nbytes} bytes, its entry holds {info.file_size}")
                data = f.read(nbytes)
                if len(data) != nbytes:
                    raise ValueError(f"{name}: {len(data)} of {nbytes} data bytes")
            array = np.frombuffer(data, dtype=dtype)
            out[name] = (array.reshape(shape[::-1]).T if fortran else array.reshape(shape)).copy()
    return out
