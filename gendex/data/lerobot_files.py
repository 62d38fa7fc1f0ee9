"""The files of a LeRobot v3.0 dataset as :mod:`gendex.data.lerobot_v3`'s writer handles them: the journaled
commit of several files at once, per-feature statistics, Arrow tables, and the data and video files kept open while
episodes stream into them."""

from __future__ import annotations

import io
import json
import logging
import os
from collections.abc import Callable
from fractions import Fraction
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
from PIL import Image

from gendex.data.episode import EpisodeError

log = logging.getLogger(__name__)

DATA_PATH = "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
VIDEO_PATH = "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4"
JOURNAL_PATH = "meta/.commit.json"
STAT_NAMES = ("min", "max", "mean", "std", "count")
QUANTILES = {"q01": 0.01, "q10": 0.10, "q50": 0.50, "q90": 0.90, "q99": 0.99}
"""lerobot 0.4's quantile stats (``compute_stats.DEFAULT_QUANTILES``, keyed ``q{int(q * 100):02d}``)."""
CONVENTIONS = (1, 2, 3)
"""How a dataset's stats are written: 1 as the published GenDex datasets (``STAT_NAMES``), 2 as lerobot 0.4 writes
them (``STAT_NAMES`` and the ``QUANTILES``, which pi0.5's quantile normalisation needs), 3 the same stats, but the
quantiles of every non-image feature in ``stats.json`` those of all the dataset's frames (see
:data:`POOLED_QUANTILES`)."""
POOLED_QUANTILES = 3
"""The conventions whose ``stats.json`` holds the quantiles of every frame of the dataset (non-image features).
lerobot 0.4 aggregates each quantile as the count-weighted mean of the episodes' (``aggregate_feature_stats``), so a
value that is constant within each episode but differs between episodes (which fingers a grasp curls) gets q01 ==
q99 while its min and max differ: pi0.5's quantile normalisation then divides by its epsilon (1e-8) and turns such
a frame into values of 1e7 and more. Images keep the episodes' mean (pi0.5 does not normalise them by quantiles)."""


class LeRobotDatasetError(EpisodeError):
    """A dataset root cannot be written as asked: it holds an incompatible or inconsistent dataset."""


def stat_names(conventions: int) -> tuple[str, ...]:
    """The stats of each feature a dataset of ``conventions`` holds, in the order they are written."""
    if type(conventions) is not int or conventions not in CONVENTIONS:
        raise LeRobotDatasetError(f"conventions {conventions!r} is not one of {list(CONVENTIONS)} (1: min/max/mean/"
                                  f"std/count as published; 2: lerobot 0.4's, with the quantiles {list(QUANTILES)}; 3: "
                                  f"as 2, the dataset's quantiles over all its frames)")
    return STAT_NAMES + (tuple(QUANTILES) if conventions >= 2 else ())


# --------------------------------------------------------------------------------------------- atomic files
def _tmp(path: Path) -> Path:
    return path.with_name(f".{path.name}.tmp")


def _json_text(obj) -> str:
    """A meta JSON file's text, as lerobot writes them."""
    return json.dumps(obj, indent=4, ensure_ascii=False) + "\n"


def _write_json(obj, path: Path) -> None:
    path.write_text(_json_text(obj), encoding="utf-8")


def _roll_forward(root: Path) -> bool:
    """Finish the renames of a committed journal left by a killed writer; True when there was one."""
    journal = root / JOURNAL_PATH
    if not journal.exists():
        return False
    for tmp_rel, final_rel in json.loads(journal.read_text())["renames"]:
        if (root / tmp_rel).exists():
            os.replace(root / tmp_rel, root / final_rel)
    journal.unlink()
    return True


def _commit(root: Path, files: list[tuple[Path, Callable[[Path], None] | None]]) -> None:
    """Write each ``(final path, writer)`` to a temp sibling (a writer None: the temp sibling is written already),
    then make them all visible through the journal."""
    staged: list[tuple[Path, Path]] = []
    try:
        for final, write in files:
            final.parent.mkdir(parents=True, exist_ok=True)
            if write is not None:
                write(_tmp(final))
            staged.append((_tmp(final), final))
    except BaseException:
        for tmp, _ in staged:
            tmp.unlink(missing_ok=True)
        raise
    journal = root / JOURNAL_PATH
    journal.parent.mkdir(parents=True, exist_ok=True)
    _write_json({"renames": [[str(t.relative_to(root)), str(f.relative_to(root))] for t, f in staged]},
                _tmp(journal))
    os.replace(_tmp(journal), journal)  # the commit point
    _roll_forward(root)


def _recover(root: Path) -> None:
    if _roll_forward(root):
        log.warning("%s: finished an interrupted commit left by a killed writer", root)
    for stray in root.rglob(".*.tmp"):
        log.warning("%s: removing incomplete temp file %s", root, stray.relative_to(root))
        stray.unlink()


# --------------------------------------------------------------------------------------------- stats
def _quantiles(x: np.ndarray) -> dict[str, np.ndarray]:
    """The :data:`QUANTILES` of ``x`` along its first axis, exactly (numpy's linear interpolation between the sorted
    values; lerobot estimates them from a histogram)."""
    values = np.quantile(x, list(QUANTILES.values()), axis=0)
    return {name: np.asarray(v, np.float64) for name, v in zip(QUANTILES, values, strict=True)}


def _pooled_quantiles(stats: dict[str, dict[str, np.ndarray]],
                      values: dict[str, list[np.ndarray]]) -> dict[str, dict[str, np.ndarray]]:
    """``stats`` with the quantiles of each feature in ``values`` replaced by those of all its frames (``values``:
    per feature, the episodes' arrays, [T] or [T, D], in any order: a quantile does not depend on it)."""
    out = dict(stats)
    for key, parts in values.items():
        x = np.concatenate([np.asarray(p, np.float64) for p in parts])
        out[key] = {**stats[key], **_quantiles(x[:, None] if x.ndim == 1 else x)}
    return out


def _numeric_values(table: pa.Table, keys: list[str]) -> dict[str, np.ndarray]:
    """The columns ``keys`` of ``table`` as float64 arrays ([T] or, for a vector feature, [T, D])."""
    out = {}
    for key in keys:
        col = table.column(key).combine_chunks()
        if pa.types.is_fixed_size_list(col.type):
            arr = col.flatten().to_numpy(zero_copy_only=False).reshape(len(col), col.type.list_size)
        else:
            arr = col.to_numpy(zero_copy_only=False)
        out[key] = np.asarray(arr, np.float64)
    return out


def pool_quantiles(root: Path | str) -> Path:
    """Rewrite the ``meta/stats.json`` of the published dataset at ``root`` (conventions 2 or 3) with the quantiles
    of every non-image feature over all its frames: conventions 3's stats, the same bytes a conventions-3 writer
    writes, without writing the dataset again. Returns the stats file's path."""
    from gendex_envs.atomic_io import write_text

    root = Path(root)
    try:
        info = json.loads((root / "meta" / "info.json").read_text())
        stats = json.loads((root / "meta" / "stats.json").read_text())
        keys = [k for k, ft in info["features"].items() if ft["dtype"] not in ("video", "image")]
        missing = [k for k in keys if not isinstance(stats.get(k), dict) or set(QUANTILES) - set(stats[k])]
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise LeRobotDatasetError(f"{root}: not a published LeRobot v3.0 dataset: meta/info.json needs a `features` "
                                  f"object of objects with a `dtype`, meta/stats.json an object per feature "
                                  f"({type(exc).__name__}: {exc})") from None
    if missing:
        raise LeRobotDatasetError(f"{root}: stats.json has no quantiles for {missing}; only a dataset written with "
                                  f"conventions 2 or 3 can have them pooled")
    paths = sorted(root.glob("data/chunk-*/file-*.parquet"))
    if not paths:
        raise LeRobotDatasetError(f"{root} holds no data/chunk-*/file-*.parquet files")
    values: dict[str, list[np.ndarray]] = {k: [] for k in keys}
    for path in paths:
        try:
            table = pq.read_table(path, columns=keys)
        except (OSError, pa.ArrowException) as exc:
            raise LeRobotDatasetError(f"{path}: not a data file with the columns {keys} ({exc})") from None
        for k, v in _numeric_values(table, keys).items():
            values[k].append(v)
    arrays = {k: {s: np.asarray(v) for s, v in d.items()} for k, d in stats.items()}
    path = root / "meta" / "stats.json"
    write_text(path, _json_text(_jsonable(_pooled_quantiles(arrays, values))))
    return path


def _array_stats(x: np.ndarray, quantiles: bool = False) -> dict[str, np.ndarray]:
    """Per-dimension stats of ``x`` ([T] or [T, D]) over its frames; with ``quantiles`` the :data:`QUANTILES` too."""
    x = np.asarray(x, dtype=np.float64)
    x = x[:, None] if x.ndim == 1 else x
    out = {"min": x.min(0), "max": x.max(0), "mean": x.mean(0), "std": x.std(0), "count": np.array([len(x)])}
    return (out | _quantiles(x)) if quantiles else out


def _image_stats(images: np.ndarray, quantiles: bool = False) -> dict[str, np.ndarray]:
    """Per-channel stats of uint8 [T, H, W, 3] images scaled to [0, 1], shaped [3, 1, 1] as lerobot's; with
    ``quantiles`` the :data:`QUANTILES` of each channel's pixels too."""
    flat = images.reshape(-1, 3)
    out = {"min": flat.min(0) / 255.0, "max": flat.max(0) / 255.0,
           "mean": flat.mean(0, dtype=np.float64) / 255.0, "std": flat.std(0, dtype=np.float64) / 255.0}
    out = {**{k: v.astype(np.float64).reshape(3, 1, 1) for k, v in out.items()}, "count": np.array([len(images)])}
    if quantiles:
        out |= {k: (v / 255.0).reshape(3, 1, 1) for k, v in _quantiles(flat).items()}
    return out


def _aggregate(stats_list: list[dict[str, dict[str, np.ndarray]]]) -> dict[str, dict[str, np.ndarray]]:
    """Merge per-episode stats: min/max over episodes, count-weighted mean and (parallel-algorithm) variance, and
    each quantile the stats hold as the count-weighted mean of the episodes' (as lerobot 0.4 aggregates them)."""
    out = {}
    for key in stats_list[0]:
        ss = [s[key] for s in stats_list]
        counts = np.array([float(s["count"][0]) for s in ss])
        means = np.stack([np.asarray(s["mean"], np.float64) for s in ss])
        var = np.stack([np.asarray(s["std"], np.float64) ** 2 for s in ss])
        w = counts.reshape(-1, *[1] * (means.ndim - 1))
        total = counts.sum()
        mean = (means * w).sum(0) / total
        variance = ((var + (means - mean) ** 2) * w).sum(0) / total
        out[key] = {"min": np.min(np.stack([np.asarray(s["min"], np.float64) for s in ss]), 0),
                    "max": np.max(np.stack([np.asarray(s["max"], np.float64) for s in ss]), 0),
                    "mean": mean, "std": np.sqrt(np.maximum(variance, 0.0)), "count": np.array([int(total)])}
        for q in (q for q in ss[0] if q in QUANTILES):
            out[key][q] = (np.stack([np.asarray(s[q], np.float64) for s in ss]) * w).sum(0) / total
    return out


def _fold(stats_list: list[dict[str, dict[str, np.ndarray]]]) -> dict[str, dict[str, np.ndarray]]:
    """The dataset's stats as a writer accumulates them, one episode at a time (``_aggregate([so_far, episode])``):
    a resumed writer rebuilds them this way, because one flat :func:`_aggregate` over every episode rounds
    differently in the last bits."""
    out = stats_list[0]
    for s in stats_list[1:]:
        out = _aggregate([out, s])
    return out


def _jsonable(stats: dict[str, dict[str, np.ndarray]]) -> dict:
    return {k: {s: np.asarray(v).tolist() for s, v in d.items()} for k, d in stats.items()}


# --------------------------------------------------------------------------------------------- tables
def _vectors(x: np.ndarray) -> pa.Array:
    x = np.ascontiguousarray(x, dtype=np.float32)
    return pa.FixedSizeListArray.from_arrays(pa.array(x.reshape(-1)), x.shape[1])


def _png_column(images: np.ndarray) -> pa.Array:
    blobs = []
    for img in images:
        buf = io.BytesIO()
        Image.fromarray(img).save(buf, format="PNG")
        blobs.append(buf.getvalue())
    return pa.StructArray.from_arrays([pa.array(blobs, pa.binary()), pa.array([None] * len(blobs), pa.string())],
                                      names=["bytes", "path"])


def _canonical(table: pa.Table) -> pa.Table:
    """``table`` with every fixed-size list typed as :func:`_vectors` makes it (item field ``item``, not parquet's
    ``element``), so that a table read back and one built in memory are written as the same bytes."""
    fields = [pa.field(f.name, pa.list_(f.type.value_type, f.type.list_size), f.nullable)
              if pa.types.is_fixed_size_list(f.type) else f for f in table.schema]
    return table.cast(pa.schema(fields))


def _tasks_table(tasks: dict[str, int]) -> pa.Table:
    """``tasks.parquet`` as pandas writes ``DataFrame({"task_index": ...}, index=Index(tasks, name="task"))``."""
    names = list(tasks)
    table = pa.table({"task_index": pa.array([tasks[t] for t in names], pa.int64()),
                      "task": pa.array(names, pa.string())})
    pandas_meta = {
        "index_columns": ["task"],
        "column_indexes": [{"name": None, "field_name": None, "pandas_type": "unicode", "numpy_type": "object",
                            "metadata": {"encoding": "UTF-8"}}],
        "columns": [{"name": "task_index", "field_name": "task_index", "pandas_type": "int64",
                     "numpy_type": "int64", "metadata": None},
                    {"name": "task", "field_name": "task", "pandas_type": "unicode", "numpy_type": "object",
                     "metadata": None}],
        "creator": {"library": "pyarrow", "version": pa.__version__},
        "pandas_version": "2.2.3",
    }
    return table.replace_schema_metadata({b"pandas": json.dumps(pandas_meta).encode()})


# --------------------------------------------------------------------------------------------- open files
class _OpenData:
    """The data file episodes are being appended to: a parquet writer on the file's hidden temp sibling, one row
    group per episode; ``size`` is the bytes written so far (the same after a resume, so file splits are too)."""

    def __init__(self, root: Path, chunk: int, file: int, schema: pa.Schema):
        self.chunk, self.file, self.rows = chunk, file, 0
        self.final = root / DATA_PATH.format(chunk_index=chunk, file_index=file)
        self.final.parent.mkdir(parents=True, exist_ok=True)
        self.sink = pa.OSFile(str(_tmp(self.final)), "wb")
        self.writer = pq.ParquetWriter(self.sink, schema)

    @property
    def size(self) -> int:
        return self.sink.tell()

    def append(self, table: pa.Table) -> None:
        self.writer.write_table(table)
        self.rows += table.num_rows

    def finish(self) -> Path:
        self.writer.close()
        self.sink.close()
        return self.final


class _OpenVideo:
    """The video file of one camera episodes are being appended to: an MP4 muxer on the file's hidden temp sibling
    into which each episode's own encoded packets are copied, shifted to start after the frames already there (as
    lerobot concatenates episode videos); ``size`` is the bytes of the packets muxed so far."""

    def __init__(self, root: Path, key: str, chunk: int, file: int, template):
        import av

        self.chunk, self.file, self.frames, self.size = chunk, file, 0, 0
        self.final = root / VIDEO_PATH.format(video_key=key, chunk_index=chunk, file_index=file)
        self.final.parent.mkdir(parents=True, exist_ok=True)
        self.container = av.open(str(_tmp(self.final)), "w", format="mp4")
        self.stream = self.container.add_stream_from_template(template, opaque=True)
        # the mp4 muxer writes max(bit rate of the template, measured average) into the btrt box: with the template's
        # rate unset, a file built from episode videos and one rebuilt from itself (a resume) are the same bytes
        self.stream.codec_context.bit_rate = 0

    def append(self, source: Path, fps: int, shift: bool = True) -> int:
        """Copy every packet of the video file ``source``; returns its frame count."""
        import av

        with av.open(str(source)) as src:
            stream = src.streams.video[0]
            offset = Fraction(self.frames, fps) / stream.time_base if shift else Fraction(0)
            if offset.denominator != 1:
                raise LeRobotDatasetError(f"{source}: time base {stream.time_base} cannot place frames at k / {fps}")
            n = 0
            for packet in src.demux(stream):
                if packet.dts is None:  # the demuxer's end-of-stream flush packet
                    continue
                packet.pts += int(offset)
                packet.dts += int(offset)
                packet.stream = self.stream
                self.size += packet.size
                self.container.mux(packet)
                n += 1
        self.frames += n
        return n

    def finish(self) -> Path:
        self.container.close()
        return self.final


def _packet_bytes(path: Path) -> int:
    """The bytes of the video packets in the file ``path`` (what muxing it into a video file adds, but the index)."""
    import av

    with av.open(str(path)) as src:
        return sum(p.size for p in src.demux(src.streams.video[0]) if p.dts is not None)


def _next_file(chunk: int, file: int, chunks_size: int) -> tuple[int, int]:
    return (chunk + 1, 0) if file + 1 >= chunks_size else (chunk, file + 1)


def _video_template(path: Path):
    import av

    container = av.open(str(path))
    return container, container.streams.video[0]
