"""The frames of a LeRobot v3.0 dataset as arrays a learner trains on (pyarrow only; no lerobot needed)."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from gendex_envs.errors import GenDexError
from gendex_envs.observation import ENVIRONMENT_STATE, STATE


class DatasetReadError(GenDexError, ValueError):
    """A folder is not a LeRobot v3.0 dataset a learner can use (no environment state, too few episodes)."""


@dataclass(frozen=True)
class Frames:
    state: np.ndarray
    """[F, S] float32 observation.state."""
    environment_state: np.ndarray
    """[F, K] float32 observation.environment_state."""
    action: np.ndarray
    """[F, A] float32."""
    episode: np.ndarray
    """[F] int64 episode index (renumbered 0.. in the order read)."""
    frame: np.ndarray
    """[F] int64 frame index within its episode."""
    names: dict[str, list[str]]
    """Feature -> column names (from meta/info.json)."""
    info: dict
    """meta/info.json."""

    @property
    def episodes(self) -> int:
        return int(self.episode.max()) + 1 if len(self.episode) else 0


def lerobot_root(path: Path | str) -> Path:
    """The LeRobot dataset in ``path``: the folder itself, its ``lerobot/``, or the one task folder of a build."""
    path = Path(path)
    tasks = sorted(p / "lerobot" for p in path.iterdir() if p.is_dir()) if path.is_dir() else []
    for cand in (path, path / "lerobot", *tasks):
        if (cand / "meta" / "info.json").is_file():
            return cand
    raise DatasetReadError(f"{path} holds no LeRobot v3.0 dataset (no meta/info.json in it, in lerobot/ or in a "
                           f"task folder of a dataset build)")


def load_frames(path: Path | str, episodes: int | None = None) -> Frames:
    """The first ``episodes`` episodes (all when None) of the dataset at ``path``."""
    root = lerobot_root(path)
    info = json.loads((root / "meta" / "info.json").read_text())
    feats = info["features"]
    for key in (STATE, ENVIRONMENT_STATE, "action"):
        if key not in feats:
            raise DatasetReadError(f"{root} has no {key!r} feature (it has {sorted(feats)}); collect it again with "
                                   f"this GenDex, which records the environment state")
    total = info["total_episodes"]
    if episodes is not None and not 1 <= episodes <= total:
        raise DatasetReadError(f"{root} holds {total} episodes; asked for {episodes} (1..{total} allowed)")
    files = sorted(root.glob("data/chunk-*/file-*.parquet"))
    table = pa.concat_tables([pq.read_table(f, columns=[STATE, ENVIRONMENT_STATE, "action", "episode_index",
                                                        "frame_index"]) for f in files])
    ep = table["episode_index"].to_numpy()
    keep = ep < (episodes if episodes is not None else total)

    def mat(key):
        col = table[key].combine_chunks()
        return np.asarray(col.flatten().to_numpy(), dtype=np.float32).reshape(len(table), -1)[keep]

    return Frames(state=mat(STATE), environment_state=mat(ENVIRONMENT_STATE), action=mat("action"),
                  episode=ep[keep].astype(np.int64), frame=table["frame_index"].to_numpy()[keep].astype(np.int64),
                  names={k: feats[k]["names"] for k in (STATE, ENVIRONMENT_STATE, "action")}, info=info)


def load_images(path: Path | str, camera: str, episodes: int | None = None, size: int | None = None) -> np.ndarray:
    """[F, size, size, 3] uint8: camera ``camera``'s frame for every row :func:`load_frames` gives (same
    ``episodes``, same order), decoded from the dataset's videos (each episode's frames located by its row in the
    episodes parquet) and, when ``size`` differs from the recorded resolution, resized by area averaging."""
    from PIL import Image

    from gendex_envs.video import decode

    root = lerobot_root(path)
    info = json.loads((root / "meta" / "info.json").read_text())
    key = f"observation.images.{camera}"
    feat = info["features"].get(key)
    if feat is None or feat.get("dtype") != "video":
        have = sorted(k.removeprefix("observation.images.") for k, f in info["features"].items()
                      if k.startswith("observation.images.") and f.get("dtype") == "video")
        raise DatasetReadError(f"{root} has no video of camera {camera!r} (cameras: {have or 'none'}); collect with "
                               f"--cameras {camera}")
    fps = info["fps"]
    rows = pa.concat_tables([pq.read_table(f) for f in sorted(root.glob("meta/episodes/chunk-*/file-*.parquet"))])
    eps = rows.to_pylist()
    total = len(eps) if episodes is None else episodes
    cache: dict[tuple[int, int], np.ndarray] = {}
    out = []
    for row in sorted(eps, key=lambda r: r["episode_index"])[:total]:
        where = (row[f"videos/{key}/chunk_index"], row[f"videos/{key}/file_index"])
        if where not in cache:
            cache.clear()  # files are read in order: one decoded file at a time
            cache[where] = decode(root / info["video_path"].format(video_key=key, chunk_index=where[0],
                                                                   file_index=where[1]))
        first = round(row[f"videos/{key}/from_timestamp"] * fps)
        frames = cache[where][first:first + row["length"]]
        if len(frames) != row["length"]:
            raise DatasetReadError(f"{root}: episode {row['episode_index']} has {row['length']} rows but its video "
                                   f"holds {len(frames)} frames from {first}")
        if size is not None and frames.shape[1:3] != (size, size):
            frames = np.stack([np.asarray(Image.fromarray(f).resize((size, size), Image.BOX)) for f in frames])
        out.append(frames)
    return np.concatenate(out)


__all__ = ["DatasetReadError", "Frames", "load_frames", "load_images", "lerobot_root"]
