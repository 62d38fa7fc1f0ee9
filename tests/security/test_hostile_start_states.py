"""Start states from an untrusted task folder are bounded and finite (issue 43, deliverable 6).

A ``start_states/<stage>.npz`` goes straight into the simulator's ``set_state``. A zip bomb is refused from the zip's
directory alone, before anything is inflated (time and memory measured); NaN, infinite or absurd values, non-float
arrays and oversized tables are refused with a :class:`StageError` naming the limit.
"""

from __future__ import annotations

import json
import time
import tracemalloc
import zipfile
from pathlib import Path

import numpy as np
import pytest

from gendex_envs.errors import StageError
from gendex_envs.start_states import StartStates


def _write(path: Path, *, state, pos=None, quat=None, meta=None) -> Path:
    """An .npz laid out like StartStates.save, with any arrays (no checks on the way out)."""
    arrays = {"state": state, "meta": np.array(json.dumps(meta or {"stage": "s", "source": "x", "objects": ["box"]}))}
    arrays["pos/box"] = np.zeros((len(state), 3), np.float32) if pos is None else pos
    arrays["quat/box"] = np.tile(np.float32([1, 0, 0, 0]), (len(state), 1)) if quat is None else quat
    np.savez_compressed(path, **arrays)
    return path


def _bomb(path: Path, nbytes: int) -> Path:
    """A start-state file whose ``state`` is ``nbytes`` of zeros: a few hundred kB on disk."""
    rows = nbytes // (128 * 4)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED, compresslevel=9) as z:
        z.writestr("meta.npy", _npy(np.array(json.dumps({"stage": "s", "source": "x", "objects": []}))))
        with z.open("state.npy", "w", force_zip64=True) as f:
            np.lib.format.write_array_header_1_0(f, {"descr": "<f4", "fortran_order": False, "shape": (rows, 128)})
            block = bytes(1 << 20)
            for _ in range(rows * 128 * 4 // len(block)):
                f.write(block)
    return path


def _npy(array: np.ndarray) -> bytes:
    import io

    buf = io.BytesIO()
    np.save(buf, array)
    return buf.getvalue()


def test_a_zip_bomb_is_refused_from_the_zip_directory_before_inflating(tmp_path):
    path = _bomb(tmp_path / "s.npz", 128 << 20)  # 128 MiB of zeros
    assert path.stat().st_size < 2_000_000
    tracemalloc.start()
    t0 = time.perf_counter()
    try:
        with pytest.raises(StageError, match=r"1342\d{5} bytes uncompressed; at most MAX_START_STATE_BYTES"):
            StartStates.load(path)
        elapsed = time.perf_counter() - t0
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert elapsed < 1.0 and peak < 5_000_000, (elapsed, peak)


@pytest.mark.parametrize("case, arrays, message", [
    ("nan", dict(state=np.float32([[0.0, np.nan]])), "NaN or infinite"),
    ("inf", dict(state=np.float32([[np.inf, 0.0]])), "NaN or infinite"),
    ("huge state", dict(state=np.float32([[1e30, 0.0]])), "MAX_STATE_ABS = 10000"),
    ("huge position", dict(state=np.zeros((1, 2), np.float32), pos=np.float32([[1e30, 0, 0]])),
     "MAX_POSITION_M = 100"),
    ("far position", dict(state=np.zeros((1, 2), np.float32), pos=np.float32([[0, 0, 5e3]])), "MAX_POSITION_M"),
    ("quaternion", dict(state=np.zeros((1, 2), np.float32), quat=np.float32([[3, 0, 0, 0]])),
     r"norm.*QUAT_NORM_TOLERANCE|unit quaternions"),
    ("integer state", dict(state=np.zeros((1, 2), np.int64)), "only float32 or float64"),
    ("too many rows", dict(state=np.zeros((100_001, 1), np.float32)), "MAX_START_STATE_ROWS = 100000"),
    ("long meta", dict(state=np.zeros((1, 2), np.float32),
                       meta={"stage": "s", "source": "x" * 70_000, "objects": ["box"]}), "MAX_META_CHARS = 65536"),
])
def test_non_finite_absurd_or_oversized_states_are_refused_with_the_limit_named(tmp_path, case, arrays, message):
    path = _write(tmp_path / "s.npz", **arrays)
    t0 = time.perf_counter()
    with pytest.raises(StageError, match=message):
        StartStates.load(path)
    assert time.perf_counter() - t0 < 1.0


def test_object_arrays_are_refused_and_good_files_still_load(tmp_path):
    path = tmp_path / "o.npz"
    np.savez(path, state=np.array([[object()]], dtype=object), meta=np.array("{}"))
    with pytest.raises(StageError):
        StartStates.load(path)
    good = _write(tmp_path / "g.npz", state=np.float32([[0.5, -93.0]]))
    states = StartStates.load(good)
    assert states.state.tolist() == [[0.5, -93.0]] and states.obj_reset_quat["box"].tolist() == [[1, 0, 0, 0]]


HOSTILE = Path(__file__).resolve().parents[1] / "data" / "hostile_r2" / "files"


@pytest.mark.parametrize("path", sorted(HOSTILE.glob("start_states_*.npz")), ids=lambda p: p.stem)
def test_the_committed_hostile_start_states_are_refused(path):
    """``tests/data/hostile_r2/files/start_states_*.npz`` (``make_files.py`` rebuilds them)."""
    with pytest.raises(StageError, match="only finite numbers|MAX_STATE_ABS|MAX_POSITION_M|QUAT_NORM|unit quat"
                                         "|only float32 or float64"):
        StartStates.load(path)


def test_the_committed_corpus_is_there():
    assert len(list(HOSTILE.glob("start_states_*.npz"))) == 6


def _reference_bytes() -> bytes:
    import io

    buf = io.BytesIO()
    rng = np.random.default_rng(0)
    q = rng.normal(size=(4, 4))
    np.savez_compressed(buf, state=rng.normal(size=(4, 6)).astype(np.float32),
                        meta=np.array(json.dumps({"stage": "s", "source": "x", "objects": ["box"]})),
                        **{"pos/box": rng.normal(size=(4, 3)).astype(np.float32),
                           "quat/box": (q / np.linalg.norm(q, axis=1, keepdims=True)).astype(np.float32)})
    return buf.getvalue()


REFERENCE = _reference_bytes()


@pytest.fixture(scope="module")
def fuzz_file(tmp_path_factory) -> Path:
    """The file each fuzz case is written to (module-scoped: hypothesis runs many cases per test call)."""
    return tmp_path_factory.mktemp("fuzz") / "s.npz"


def test_the_reference_file_loads(fuzz_file):
    fuzz_file.write_bytes(REFERENCE)
    assert len(StartStates.load(fuzz_file)) == 4


from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


@settings(max_examples=300, derandomize=True, database=None, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(edits=st.lists(st.tuples(st.integers(0, len(REFERENCE) - 1), st.integers(0, 255)), min_size=1, max_size=8),
       cut=st.one_of(st.none(), st.integers(0, len(REFERENCE))))
def test_fuzz_the_start_state_loader_finds_only_stage_errors(fuzz_file, edits, cut):
    """Byte edits and truncations of a valid file: it loads with finite, bounded values, or a StageError."""
    data = bytearray(REFERENCE)
    for offset, value in edits:
        data[offset] = value
    fuzz_file.write_bytes(bytes(data[:cut]))
    try:
        states = StartStates.load(fuzz_file)
    except StageError:
        return
    assert np.isfinite(states.state).all() and np.abs(states.state).max() <= 10_000
