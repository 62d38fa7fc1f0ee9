"""Write :class:`~gendex.data.episode.Episode` records as a LeRobot **v3.0** dataset with pyarrow only.

Layout (as lerobot's ``LeRobotDataset`` reads it)::

    meta/info.json                               codebase_version "v3.0", totals, features, path templates
    meta/stats.json                              per feature min/max/mean/std/count (images: per channel, [3,1,1]);
                                                 with ``conventions=2`` also the quantiles q01/q10/q50/q90/q99
    meta/tasks.parquet                           task_index column; the task string is the pandas index
    meta/episodes/chunk-000/file-000.parquet     one row per episode (+ per-episode ``stats/<feature>/<stat>``, and
                                                 ``appearance`` for a task with a scene)
    data/chunk-CCC/file-FFF.parquet              one row per action (frame); images as struct<bytes PNG, path>
    videos/<key>/chunk-CCC/file-FFF.mp4          with ``video_codec``: a camera's frames instead, episode after
                                                 episode (frame k of an episode at from_timestamp + k / fps), located
                                                 by the episode row's ``videos/<key>/{chunk_index,file_index,
                                                 from_timestamp,to_timestamp}``

Frame ``t`` of an episode holds ``observation.state = state[t]``, ``action = action[t]``, the images of step ``t``,
``next.reward/next.success = reward[t]/success[t]`` and ``next.done`` (True on the last frame), as lerobot's
``pusht``-style datasets do. The final observation ``state[T]`` is not stored (there is no action for it).

Files are split as lerobot splits them: a data file takes episodes (one parquet row group each) until the next one
would pass ``data_files_size_in_mb``, a video file until the next episode's packets would pass
``video_files_size_in_mb`` (500 MB); then a new file is started, and a new chunk after ``chunks_size`` files.

Cost and durability: :meth:`LeRobotV3Writer.add_episode` costs in proportion to that episode, not to the dataset. It
writes the episode to a journal (``meta/.pending/episode-NNNNNN.arrow``, its rows and stats, and one MP4 per camera
with its frames; the ``.arrow`` file, written atomically last, is the entry's commit point), then appends its rows as
a row group to the open data file and copies its video packets into each camera's open video file. Open and
finished-but-unpublished files are hidden temp siblings (``.<name>.tmp``). :meth:`~LeRobotV3Writer.close` publishes
them with the meta (``info.json``, ``stats.json``, ``tasks.parquet``, the episodes parquet, written whole: small)
in one journaled commit: the temp names and the renames are listed in ``meta/.commit.json``, itself renamed into
place (the commit point), then the renames are made, data and videos first and ``info.json`` last; then the journal
is cleared. So:

* the visible files always form the dataset as of the last ``close()``: complete, consistent and readable by lerobot
  (episodes added since are not visible until the writer closes);
* a writer killed at any point loses no episode that ``add_episode`` returned: the next writer removes the temp
  files, rolls a committed close forward, reopens the last data and video files (copied row group by row group,
  packet by packet) and appends the journaled episodes again. The files it ends with are the bytes an uninterrupted
  writer writes.

``conventions`` (:data:`~gendex.data.lerobot_files.CONVENTIONS`) chooses the stats: 1 (the default) writes
min/max/mean/std/count, as the published GenDex datasets hold them; 2 writes lerobot 0.4's stats, those and the
quantiles q01, q10, q50, q90 and q99 (pi0.5 normalises state and action by q01/q99): each episode's exact quantiles
per dimension (images: per channel over every pixel, scaled to [0, 1]) in its episode row, and in ``stats.json`` their
count-weighted mean over the episodes, as lerobot aggregates them; 3 writes the same, but in ``stats.json`` the
quantiles of each non-image feature over all the dataset's frames (a value constant within episodes that differ
otherwise collapses to q01 == q99 in lerobot's mean: :data:`~gendex.data.lerobot_files.POOLED_QUANTILES`). A root is
appended to only with the stats it was written with (2 and 3 hold the same stat names: the writer cannot tell them
apart on disk).

One writer per root at a time.
"""

from __future__ import annotations

import json
import logging
import shutil
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from gendex.data.episode import Episode, EpisodeError
from gendex.data.lerobot_files import (
    CONVENTIONS,
    DATA_PATH,
    POOLED_QUANTILES,
    QUANTILES,
    STAT_NAMES,
    VIDEO_PATH,
    LeRobotDatasetError,
    _aggregate,
    _array_stats,
    _canonical,
    _commit,
    _fold,
    _image_stats,
    _jsonable,
    _next_file,
    _numeric_values,
    _OpenData,
    _OpenVideo,
    _packet_bytes,
    _png_column,
    _pooled_quantiles,
    _recover,
    _tasks_table,
    _tmp,
    _vectors,
    _write_json,
    stat_names,
)
from gendex_envs.atomic_io import write_bytes, write_text
from gendex_envs.video import CODECS, PIX_FMT, encode

log = logging.getLogger(__name__)

CODEBASE_VERSION = "v3.0"
EPISODES_PATH = "meta/episodes/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
APPEARANCE = "appearance"
"""Column of the episodes parquet with what each episode looked like (``Episode.appearance`` as JSON); present only
in a dataset of a task with a ``scene`` section."""
INFO_PATH, STATS_PATH, TASKS_PATH = ("meta/info.json", "meta/stats.json", "meta/tasks.parquet")
PENDING_DIR = "meta/.pending"  # the journal: episodes added since the last close
DEFAULT_VIDEO_FILE_SIZE_IN_MB = 500
# lerobot's DEFAULT_FEATURES (the index columns every dataset has)
INDEX_FEATURES = {k: {"dtype": d, "shape": [1], "names": None} for k, d in
                  [("timestamp", "float32"), ("frame_index", "int64"), ("episode_index", "int64"),
                   ("index", "int64"), ("task_index", "int64")]}
STEP_FEATURES = {"next.reward": "float32", "next.success": "bool", "next.done": "bool"}
_ARROW = {"float32": pa.float32(), "int64": pa.int64(), "bool": pa.bool_()}




def read_episode_frames(root: Path | str) -> pa.Table:
    """All frames of the dataset at ``root``, in order (every ``data/chunk-*/file-*.parquet`` concatenated)."""
    paths = sorted(Path(root).glob("data/chunk-*/file-*.parquet"))
    if not paths:
        raise LeRobotDatasetError(f"{root} holds no data/chunk-*/file-*.parquet files; write episodes first")
    return pa.concat_tables([pq.read_table(p) for p in paths])


# --------------------------------------------------------------------------------------------- writer
class LeRobotV3Writer:
    """Append :class:`Episode` records to a LeRobot v3.0 dataset at ``root`` (created, or resumed when it exists).

    ``cameras`` maps camera name -> (height, width); those images are stored as ``observation.images.<name>``.
    ``data_files_size_in_mb`` / ``video_files_size_in_mb`` are the sizes at which a new data / video file is started
    (lerobot's defaults: 100 MB and 500 MB). ``conventions`` chooses the stats (1: as published; 2: lerobot 0.4's,
    with quantiles; see the module doc). The dataset is complete and readable after :meth:`close`; episodes added
    since the last close are kept in a journal, so a killed writer loses none of them (see the module doc).
    """

    def __init__(self, root: Path | str, *, fps: int, robot_type: str, state_names: list[str],
                 action_names: list[str], cameras: dict[str, tuple[int, int]] | None = None,
                 environment_state_names: list[str] | None = None, video_codec: str | None = None,
                 chunks_size: int = 1000, data_files_size_in_mb: float = 100,
                 video_files_size_in_mb: float = DEFAULT_VIDEO_FILE_SIZE_IN_MB,
                 codebase_version: str = CODEBASE_VERSION, conventions: int = 1):
        if codebase_version != CODEBASE_VERSION:
            raise LeRobotDatasetError(f"codebase_version {codebase_version!r} is not supported; only "
                                      f"{CODEBASE_VERSION!r} is")
        if fps <= 0 or chunks_size <= 0 or data_files_size_in_mb <= 0 or video_files_size_in_mb <= 0:
            raise LeRobotDatasetError(f"fps ({fps}), chunks_size ({chunks_size}), data_files_size_in_mb "
                                      f"({data_files_size_in_mb}) and video_files_size_in_mb "
                                      f"({video_files_size_in_mb}) must be positive")
        self.stat_names = stat_names(conventions)  # checks conventions
        self.conventions = conventions
        self.root = Path(root)
        self.fps, self.robot_type = int(fps), robot_type
        self.state_names, self.action_names = list(state_names), list(action_names)
        self.environment_state_names = list(environment_state_names or [])
        if video_codec is not None and video_codec not in CODECS:
            raise LeRobotDatasetError(f"video_codec {video_codec!r} is not one of {sorted(CODECS)} (or None: images "
                                      f"as PNG inside the parquet files)")
        self.video_codec = video_codec
        self.cameras = {k: (int(h), int(w)) for k, (h, w) in (cameras or {}).items()}
        self.chunks_size, self.data_files_size_in_mb = int(chunks_size), data_files_size_in_mb
        self.video_files_size_in_mb = video_files_size_in_mb
        self.features = self._declared_features()
        self._rows: list[dict] = []  # episodes parquet rows
        self._tasks: dict[str, int] = {}
        self._stats: dict | None = None
        self._values: dict[str, list[np.ndarray]] = {}  # conventions 3: every frame's non-image values
        self._n_frames = 0
        self._data: _OpenData | None = None
        self._videos: dict[str, _OpenVideo] = {}
        self._finished: list[Path] = []  # files complete at their hidden temp names, published at close
        self._published = 0  # episodes the visible meta holds
        self._closed = False
        self.root.mkdir(parents=True, exist_ok=True)
        _recover(self.root)
        if (self.root / INFO_PATH).exists():
            self._resume()
        else:
            if any(self.root.glob("data/*/*.parquet")):
                raise LeRobotDatasetError(f"{self.root} has data files but no {INFO_PATH}; use an empty or "
                                          f"complete LeRobot v3.0 root")
            _commit(self.root, [(self.root / INFO_PATH, lambda p: _write_json(self._info(0, 0, {}), p))])
            log.info("created LeRobot v3.0 dataset at %s", self.root)
        self._replay()

    # -- context manager
    def __enter__(self) -> LeRobotV3Writer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    @property
    def total_episodes(self) -> int:
        return len(self._rows)

    @property
    def total_frames(self) -> int:
        return self._n_frames

    def _declared_features(self) -> dict[str, dict]:
        feats = {"observation.state": {"dtype": "float32", "shape": [len(self.state_names)],
                                       "names": self.state_names},
                 "action": {"dtype": "float32", "shape": [len(self.action_names)], "names": self.action_names}}
        if self.environment_state_names:
            feats["observation.environment_state"] = {"dtype": "float32",
                                                      "shape": [len(self.environment_state_names)],
                                                      "names": self.environment_state_names}
        for cam, (h, w) in self.cameras.items():
            feats[f"observation.images.{cam}"] = {"dtype": "image", "shape": [h, w, 3],
                                                  "names": ["height", "width", "channels"]}
            if self.video_codec is not None:
                feats[f"observation.images.{cam}"] |= {"dtype": "video", "info": {
                    "video.height": h, "video.width": w, "video.codec": CODECS[self.video_codec][0],
                    "video.pix_fmt": PIX_FMT, "video.is_depth_map": False, "video.fps": self.fps,
                    "video.channels": 3, "has_audio": False}}
        feats.update({k: {"dtype": d, "shape": [1], "names": None} for k, d in STEP_FEATURES.items()})
        feats.update({k: dict(v) for k, v in INDEX_FEATURES.items()})
        return feats

    def _info(self, n_episodes: int, n_frames: int, tasks: dict[str, int]) -> dict:
        return {"codebase_version": CODEBASE_VERSION, "robot_type": self.robot_type,
                "total_episodes": n_episodes, "total_frames": n_frames, "total_tasks": len(tasks),
                "chunks_size": self.chunks_size, "data_files_size_in_mb": self.data_files_size_in_mb,
                "video_files_size_in_mb": self.video_files_size_in_mb, "fps": self.fps,
                "splits": {"train": f"0:{n_episodes}"} if n_episodes else {},
                "data_path": DATA_PATH, "video_path": VIDEO_PATH if self.video_codec is not None else None,
                "features": self.features}

    def _resume(self) -> None:
        info = json.loads((self.root / INFO_PATH).read_text())
        if info.get("codebase_version") != CODEBASE_VERSION:
            raise LeRobotDatasetError(f"{self.root} is a LeRobot {info.get('codebase_version')} dataset; only "
                                      f"{CODEBASE_VERSION} datasets can be appended to")
        if info["fps"] != self.fps or info["features"] != self.features:
            theirs, ours = info["features"], self.features
            diff = sorted(k for k in set(theirs) | set(ours) if theirs.get(k) != ours.get(k))
            raise LeRobotDatasetError(f"{self.root} holds a dataset at {info['fps']} fps whose features differ from "
                                      f"this writer's (fps {self.fps}) in {diff}; append only with the same fps, "
                                      f"state/action names and cameras, or write to a new root")
        self.chunks_size, self.data_files_size_in_mb = info["chunks_size"], info["data_files_size_in_mb"]
        self.video_files_size_in_mb = info.get("video_files_size_in_mb", DEFAULT_VIDEO_FILE_SIZE_IN_MB)
        for path in sorted(self.root.glob("meta/episodes/chunk-*/file-*.parquet")):
            self._rows.extend(pq.read_table(path).to_pylist())
        if self._rows:
            self._check_stat_names({s for s in (*STAT_NAMES, *QUANTILES) if f"stats/action/{s}" in self._rows[0]},
                                   "its episodes parquet")
        if (self.root / TASKS_PATH).exists():
            t = pq.read_table(self.root / TASKS_PATH)
            self._tasks = dict(zip(t["task"].to_pylist(), t["task_index"].to_pylist(), strict=True))
        self._n_frames = self._rows[-1]["dataset_to_index"] if self._rows else 0
        n_rows = sum(pq.read_metadata(p).num_rows for p in self.root.glob("data/chunk-*/file-*.parquet"))
        if (len(self._rows), self._n_frames) != (info["total_episodes"], info["total_frames"]) \
                or n_rows != self._n_frames:
            raise LeRobotDatasetError(
                f"{self.root} is inconsistent: info.json claims {info['total_episodes']} episodes / "
                f"{info['total_frames']} frames, the episodes parquet {len(self._rows)} / {self._n_frames}, the "
                f"data files hold {n_rows} rows; they must agree before episodes can be appended")
        self._published = len(self._rows)
        if self._rows:
            self._stats = _fold([self._row_stats(r) for r in self._rows])
            if self.conventions == POOLED_QUANTILES:
                for path in sorted(self.root.glob("data/chunk-*/file-*.parquet")):
                    self._keep_values(pq.read_table(path, columns=self._pooled_keys()))
            self._reopen(self._rows[-1])
        log.info("resuming %s: %d episodes, %d frames, %d tasks", self.root, len(self._rows), self._n_frames,
                 len(self._tasks))

    def _check_stat_names(self, theirs: set[str], where: str) -> None:
        if theirs != set(self.stat_names):
            conventions = [c for c in CONVENTIONS if set(stat_names(c)) == theirs]
            known = (*STAT_NAMES, *QUANTILES)
            named = [s for s in known if s in theirs] + sorted(theirs - set(known))
            raise LeRobotDatasetError(
                f"{self.root}: {where} holds the stats {', '.join(named)}"
                f"{f' (conventions {conventions[0]})' if conventions else ''}; this writer has conventions "
                f"{self.conventions} ({', '.join(self.stat_names)}): append only with the conventions the dataset "
                f"was written with, or write to a new root")

    def _reopen(self, last: dict) -> None:
        """Continue the last data and video files: their content is copied to new open files (row group by row
        group, packet by packet), which then end as the same bytes as if the writer had never stopped."""
        chunk, file = last["data/chunk_index"], last["data/file_index"]
        source = pq.ParquetFile(self.root / DATA_PATH.format(chunk_index=chunk, file_index=file))
        # read back as this writer builds tables (parquet names a list's item "element", the in-memory one "item")
        groups = [_canonical(source.read_row_group(i)) for i in range(source.num_row_groups)]
        self._data = _OpenData(self.root, chunk, file, groups[0].schema)
        for group in groups:
            self._data.append(group)
        for key, ft in self.features.items():
            if ft["dtype"] == "video":
                path = self.root / VIDEO_PATH.format(video_key=key, chunk_index=last[f"videos/{key}/chunk_index"],
                                                     file_index=last[f"videos/{key}/file_index"])
                self._videos[key] = self._open_video(key, last[f"videos/{key}/chunk_index"],
                                                     last[f"videos/{key}/file_index"], path)
                self._videos[key].append(path, self.fps, shift=False)

    def _open_video(self, key: str, chunk: int, file: int, template_path: Path) -> _OpenVideo:
        import av

        with av.open(str(template_path)) as container:
            return _OpenVideo(self.root, key, chunk, file, container.streams.video[0])

    def _replay(self) -> None:
        """Append the journaled episodes a killed writer added after the last close (none after a clean close)."""
        pending = self.root / PENDING_DIR
        if not pending.is_dir():
            return
        entries = {int(p.name[8:14]): p for p in pending.glob("episode-??????.arrow")}
        for path in sorted(pending.iterdir()):  # an episode killed before its entry was complete, or published
            index = int(path.name[8:14]) if path.name[8:14].isdigit() else -1
            if index not in entries or index < self._published:
                path.unlink()
        if not entries.keys() - set(range(self._published)):
            shutil.rmtree(pending)
            return
        replayed = 0
        for e in sorted(i for i in entries if i >= self._published):
            if e != len(self._rows):
                raise LeRobotDatasetError(f"{pending} journals episode {e} but the dataset holds {len(self._rows)} "
                                          f"episodes; a journaled episode is missing, so the root cannot be resumed")
            with pa.ipc.open_file(entries[e]) as reader:
                table = reader.read_all()
            meta = json.loads(table.schema.metadata[b"gendex"])
            for d in meta["stats"].values():
                self._check_stat_names(set(d), f"its journal entry {entries[e].name}")
            stats = {k: {s: np.asarray(v) for s, v in d.items()} for k, d in meta["stats"].items()}
            self._append(table.replace_schema_metadata(None), meta["instruction"], stats, self._segments(e),
                         meta.get("appearance"))
            replayed += 1
        if replayed:
            log.warning("%s: a writer was killed before closing; %d journaled episodes appended again", self.root,
                        replayed)

    def _segments(self, e: int) -> dict[str, Path]:
        return {k: self.root / PENDING_DIR / f"episode-{e:06d}.{k}.mp4" for k, ft in self.features.items()
                if ft["dtype"] == "video"}

    def _pooled_keys(self) -> list[str]:
        return [k for k, ft in self.features.items() if ft["dtype"] not in ("video", "image")]

    def _keep_values(self, table: pa.Table) -> None:
        """Conventions 3: keep the non-image columns of ``table`` (an episode's rows, or a published data file's)
        for the dataset's quantiles."""
        for key, arr in _numeric_values(table, self._pooled_keys()).items():
            self._values.setdefault(key, []).append(arr)

    def _row_stats(self, row: dict) -> dict[str, dict[str, np.ndarray]]:
        return {k: {s: np.asarray(row[f"stats/{k}/{s}"]) for s in self.stat_names} for k in self.features}

    def _validate(self, ep: Episode) -> None:
        who = f"episode of {ep.task_id} (seed {ep.seed})"
        if ep.fps != self.fps:
            raise EpisodeError(f"{who} was recorded at {ep.fps} fps; this dataset is {self.fps} fps (only equal "
                               f"fps is allowed)")
        t = ep.length
        checks = [("state", ep.state, t + 1, self.state_names), ("action", ep.action, t, self.action_names)]
        if self.environment_state_names:
            if ep.environment_state is None or list(ep.environment_state_names) != self.environment_state_names:
                raise EpisodeError(f"{who} has environment state named {list(ep.environment_state_names)[:4]}...; "
                                   f"this dataset declares {self.environment_state_names[:4]}... (the same task "
                                   f"and objects are needed)")
            checks.append(("environment_state", ep.environment_state, t + 1, self.environment_state_names))
        for key, arr, rows, names in checks:
            arr = np.asarray(arr)
            if arr.shape != (rows, len(names)):
                raise EpisodeError(f"{who}: {key} has shape {arr.shape}; this dataset declares {len(names)} "
                                   f"{key} values ({', '.join(names[:4])}{', ...' if len(names) > 4 else ''}), "
                                   f"so only shape ({rows}, {len(names)}) is allowed")
            if not np.all(np.isfinite(arr)):
                raise EpisodeError(f"{who}: {key} contains NaN or inf; only finite values are allowed")
        if not isinstance(ep.instruction, str) or not ep.instruction.strip():
            raise EpisodeError(f"{who}: instruction {ep.instruction!r} is empty; a non-empty task string is needed")
        for cam, (h, w) in self.cameras.items():
            if cam not in ep.images:
                raise EpisodeError(f"{who} has no images for camera {cam!r}; it has {sorted(ep.images)} and the "
                                   f"dataset declares {sorted(self.cameras)}")
            img = ep.images[cam]
            if img.dtype != np.uint8 or img.shape != (t + 1, h, w, 3):
                raise EpisodeError(f"{who}: images[{cam!r}] is {img.dtype} {img.shape}; only uint8 "
                                   f"({t + 1}, {h}, {w}, 3) is allowed")
        extra = sorted(set(ep.images) - set(self.cameras))
        if extra:
            log.debug("%s: cameras %s are not declared and are not exported", who, extra)

    def add_episode(self, ep: Episode) -> int:
        """Append ``ep`` (its ``T`` actions become ``T`` frames); returns its episode_index. It is journaled before
        this returns, and in the dataset's visible files once the writer is closed."""
        if self._closed:
            raise LeRobotDatasetError(f"the writer of {self.root} is closed; open a new LeRobotV3Writer to append")
        self._validate(ep)
        t, e, start = ep.length, len(self._rows), self._n_frames
        task_index = self._tasks.get(ep.instruction, len(self._tasks))
        done = np.zeros(t, bool)
        done[-1] = True
        numeric = {"observation.state": np.asarray(ep.state[:t], np.float32),
                   "action": np.asarray(ep.action, np.float32),
                   "next.reward": np.asarray(ep.reward, np.float32), "next.success": np.asarray(ep.success, bool),
                   "next.done": done, "timestamp": (np.arange(t) / self.fps).astype(np.float32),
                   "frame_index": np.arange(t, dtype=np.int64), "episode_index": np.full(t, e, np.int64),
                   "index": np.arange(start, start + t, dtype=np.int64),
                   "task_index": np.full(t, task_index, np.int64)}
        if self.environment_state_names:
            numeric["observation.environment_state"] = np.asarray(ep.environment_state[:t], np.float32)
        columns, ep_stats, videos, quantiles = {}, {}, {}, self.conventions >= 2
        for key, ft in self.features.items():
            if ft["dtype"] == "video":
                images = ep.images[key.removeprefix("observation.images.")][:t]
                ep_stats[key], videos[key] = _image_stats(images, quantiles), images
            elif ft["dtype"] == "image":
                images = ep.images[key.removeprefix("observation.images.")][:t]
                columns[key], ep_stats[key] = _png_column(images), _image_stats(images, quantiles)
            else:
                arr = numeric[key]
                columns[key] = _vectors(arr) if arr.ndim == 2 else pa.array(arr, _ARROW[ft["dtype"]])
                ep_stats[key] = _array_stats(arr, quantiles)
        table = pa.table(columns)
        # the journal entry: each camera's frames as their own video, then the rows and stats (its commit point)
        segments = self._segments(e)
        (self.root / PENDING_DIR).mkdir(parents=True, exist_ok=True)
        try:
            for key, path in segments.items():
                encode(videos[key], path, self.fps, self.video_codec)
            meta = {"instruction": ep.instruction, "stats": _jsonable(ep_stats)}
            if ep.appearance:
                meta["appearance"] = ep.appearance
            entry = table.replace_schema_metadata({"gendex": json.dumps(meta)})
            sink = pa.BufferOutputStream()
            with pa.ipc.new_file(sink, entry.schema) as ipc:
                ipc.write_table(entry)
            write_bytes(self.root / PENDING_DIR / f"episode-{e:06d}.arrow", sink.getvalue().to_pybytes())
        except BaseException:
            for path in segments.values():
                path.unlink(missing_ok=True)
            raise
        self._append(table, ep.instruction, ep_stats, segments, ep.appearance)
        log.debug("%s: wrote episode %d (%d frames) to data chunk %d file %d", self.root, e, t, self._data.chunk,
                  self._data.file)
        return e

    def _append(self, table: pa.Table, instruction: str, ep_stats: dict, segments: dict[str, Path],
                appearance: dict | None = None) -> None:
        """Add a journaled episode to the open data and video files (new ones when a size limit would be passed);
        its episodes row keeps the episode's ``appearance`` (JSON) when it has one."""
        e, t, start, r = len(self._rows), table.num_rows, self._n_frames, self.root
        try:
            data = self._data
            if data is not None and data.rows and \
                    data.size * (1 + t / data.rows) >= self.data_files_size_in_mb * 1024 * 1024:
                self._finished.append(data.finish())
                self._data = _OpenData(r, *_next_file(data.chunk, data.file, self.chunks_size), table.schema)
            elif data is None:
                self._data = _OpenData(r, 0, 0, table.schema)
            self._data.append(table)
            row = {"episode_index": e, "tasks": [instruction], "length": t, "data/chunk_index": self._data.chunk,
                   "data/file_index": self._data.file, "dataset_from_index": start, "dataset_to_index": start + t,
                   "meta/episodes/chunk_index": 0, "meta/episodes/file_index": 0}
            for key, segment in segments.items():
                video, size = self._videos.get(key), _packet_bytes(segment)
                if video is None:
                    video = self._videos[key] = self._open_video(key, 0, 0, segment)
                elif video.frames and video.size + size >= self.video_files_size_in_mb * 1024 * 1024:
                    self._finished.append(video.finish())
                    video = self._videos[key] = self._open_video(
                        key, *_next_file(video.chunk, video.file, self.chunks_size), segment)
                first = video.frames
                video.append(segment, self.fps)
                row.update({f"videos/{key}/chunk_index": video.chunk, f"videos/{key}/file_index": video.file,
                            f"videos/{key}/from_timestamp": first / self.fps,
                            f"videos/{key}/to_timestamp": video.frames / self.fps})
        except BaseException:
            self._abandon()
            log.error("%s: appending episode %d was interrupted; it is journaled: open a new writer to go on", r, e)
            raise
        if appearance:
            row[APPEARANCE] = json.dumps(appearance, sort_keys=True)
        row.update({f"stats/{k}/{s}": (np.asarray(v).astype(np.int64) if s == "count" else np.asarray(v)).tolist()
                    for k, d in ep_stats.items() for s, v in d.items()})
        self._rows.append(row)
        self._tasks.setdefault(instruction, len(self._tasks))
        self._stats = ep_stats if self._stats is None else _aggregate([self._stats, ep_stats])
        if self.conventions == POOLED_QUANTILES:
            self._keep_values(table)
        self._n_frames = start + t

    def _abandon(self) -> None:
        """Stop without publishing: close the open files and remove every unpublished one (the journal stays)."""
        self._closed = True
        opened = ([self._data] if self._data is not None else []) + list(self._videos.values())
        for f in opened:
            try:
                f.finish()
            except Exception:  # a half-written temp file is removed below either way
                pass
        for path in [*self._finished, *(f.final for f in opened)]:
            _tmp(path).unlink(missing_ok=True)
        self._data, self._videos, self._finished = None, {}, []

    def close(self) -> None:
        """Publish the episodes added since the writer was opened (data and video files, meta) in one journaled
        commit, and clear the journal. After it the dataset is complete and readable by lerobot."""
        if self._closed:
            return
        if len(self._rows) == self._published:
            self._abandon()
            return
        self._closed = True
        r = self.root
        try:
            files = [*self._finished, *([self._data.finish()] if self._data is not None else []),
                     *(v.finish() for v in self._videos.values())]
            self._data, self._videos, self._finished = None, {}, []
            rows, tasks, stats = self._rows, self._tasks, self._stats
            if self.conventions == POOLED_QUANTILES:
                stats = _pooled_quantiles(stats, self._values)
            if any(APPEARANCE in row for row in rows):  # one column for all rows: parquet takes the first's keys
                rows = [row if APPEARANCE in row else {**row, APPEARANCE: "{}"} for row in rows]
            info = self._info(len(rows), self._n_frames, tasks)
            _commit(r, [*((f, None) for f in files),
                        (r / TASKS_PATH, lambda p: pq.write_table(_tasks_table(tasks), p)),
                        (r / EPISODES_PATH.format(chunk_index=0, file_index=0),
                         lambda p: pq.write_table(pa.Table.from_pylist(rows), p)),
                        (r / STATS_PATH, lambda p: _write_json(_jsonable(stats), p)),
                        (r / INFO_PATH, lambda p: _write_json(info, p))])
        except BaseException:
            log.error("%s: closing was interrupted; the episodes are journaled: a new writer publishes them", r)
            raise
        shutil.rmtree(r / PENDING_DIR, ignore_errors=True)
        self._published = len(rows)
        log.info("closed %s: %d episodes, %d frames", r, len(rows), self._n_frames)

    finalize = close


def write_dataset_card(root: Path | str, *, task_id: str, instruction: str, robot: str, env_kwargs: dict,
                       n_episodes: int, n_frames: int, how_made: str) -> Path:
    """Write a LeRobot-style ``README.md`` (YAML front matter + description) at ``root``; returns its path.

    ``env_kwargs`` are the exact ``gym.make`` keyword arguments the episodes were recorded with: the card shows the
    call, so a policy learned from the data acts in the same action space."""
    root = Path(root)
    make = ", ".join([repr(task_id)] + [f"{k}={v!r}" for k, v in env_kwargs.items()])
    info_path = root / INFO_PATH
    structure = ("[meta/info.json](meta/info.json):\n\n```json\n" + info_path.read_text().strip() + "\n```\n"
                 if info_path.exists() else "")
    text = f"""---
license: apache-2.0
task_categories:
- robotics
tags:
- LeRobot
- gendex
- shadowhand
configs:
- config_name: default
  data_files: data/*/*.parquet
---

# {task_id}

This dataset was created with GenDex and follows the [LeRobot](https://github.com/huggingface/lerobot)
v3.0 dataset format.

- **Task**: `{task_id}`
- **Instruction**: {instruction}
- **Robot**: {robot}
- **Control mode**: `{env_kwargs.get("control_mode", "pd_joint_pos")}`
- **Episodes**: {n_episodes}
- **Frames**: {n_frames}

## The environment the data comes from

```python
import gymnasium as gym
import gendex_envs  # registers the GenDex task ids
from gendex_envs.observation import LeRobotObservation

env = LeRobotObservation(gym.make({make}))
obs, info = env.reset(seed=0)  # obs: the features below, by the same names, for one frame
```

Every `action` row is an action of this env (its `action_space`). `observation.state` lists the robot's joint
positions then velocities; `observation.environment_state`, where present, every task object's position and
orientation (wxyz), each articulated object's joint positions and the goal mark's position; both are named column
by column in `meta/info.json`. `LeRobotObservation` returns exactly these features (and the camera images, with
`obs_mode="rgb"`), so a policy trained on this data runs in the env as it is.

## How it was made

{how_made}

## Dataset structure

{structure}"""
    return write_text(root / "README.md", text, encoding="utf-8")
