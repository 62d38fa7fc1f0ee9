"""LeRobot v3.0 writer on synthetic episodes: layout, schemas, stats, resume and crash consistency (no simulator)."""

from __future__ import annotations

import hashlib
import io
import json
import os
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq
import pytest
import yaml
from PIL import Image

from gendex.data import lerobot_files
from gendex.data import lerobot_v3 as lv3
from gendex.data.episode import Episode, EpisodeError
from gendex.data.lerobot_v3 import LeRobotDatasetError, LeRobotV3Writer, read_episode_frames, write_dataset_card

S, A, H, W, FPS = 5, 3, 8, 6, 20
STATE_NAMES = [f"q{i}" for i in range(S)]
ACTION_NAMES = [f"a{i}" for i in range(A)]


def make_episode(t: int, seed: int, instruction: str = "put the apple in the bowl", cams=("front",),
                 s: int = S, a: int = A, fps: int = FPS) -> Episode:
    rng = np.random.default_rng(seed)
    success = np.zeros(t, bool)
    success[-1] = seed % 2 == 0
    return Episode(task_id="GenDex/PutAppleBowl-v0", instruction=instruction, seed=seed, control_mode="pd_joint_pos",
                   control_joint="all", fps=fps, state=rng.normal(size=(t + 1, s)).astype(np.float32),
                   action=rng.uniform(-1, 1, size=(t, a)).astype(np.float32),
                   reward=rng.uniform(size=t).astype(np.float32), success=success, fail=np.zeros(t, bool),
                   env_states=np.zeros((t + 1, 2), np.float32),
                   images={c: rng.integers(0, 256, size=(t + 1, H, W, 3), dtype=np.uint8) for c in cams})


def writer(root: Path, **kw) -> LeRobotV3Writer:
    args = dict(fps=FPS, robot_type="shadowhand_ur10e", state_names=STATE_NAMES, action_names=ACTION_NAMES,
                cameras={"front": (H, W)})
    return LeRobotV3Writer(root, **{**args, **kw})


def meta(root: Path) -> tuple[dict, dict, pa.Table]:
    info = json.loads((root / "meta/info.json").read_text())
    stats = json.loads((root / "meta/stats.json").read_text())
    eps = pa.concat_tables([pq.read_table(p) for p in sorted(root.glob("meta/episodes/chunk-*/file-*.parquet"))])
    return info, stats, eps


def assert_consistent(root: Path) -> None:
    """meta totals == parquet rows, and each episode row points at its frames."""
    info, _, eps = meta(root)
    frames = read_episode_frames(root)
    assert info["total_frames"] == frames.num_rows == sum(eps["length"].to_pylist())
    assert info["total_episodes"] == eps.num_rows
    assert info["splits"] == {"train": f"0:{eps.num_rows}"}
    assert frames["index"].to_pylist() == list(range(frames.num_rows))
    for ep in eps.to_pylist():
        path = root / info["data_path"].format(chunk_index=ep["data/chunk_index"], file_index=ep["data/file_index"])
        rows = pq.read_table(path).filter(pc.equal(pc.field("episode_index"), ep["episode_index"]))
        assert rows.num_rows == ep["length"]
        assert rows["index"].to_pylist() == list(range(ep["dataset_from_index"], ep["dataset_to_index"]))
        assert rows["frame_index"].to_pylist() == list(range(ep["length"]))


@pytest.fixture
def episodes():
    return [make_episode(7, 0), make_episode(4, 1, instruction="open the drawer"), make_episode(5, 2)]


@pytest.fixture
def dataset(tmp_path, episodes):
    root = tmp_path / "ds"
    with writer(root) as w:
        assert [w.add_episode(e) for e in episodes] == [0, 1, 2]
    return root


def test_layout_files_exist(dataset):
    for rel in ["meta/info.json", "meta/stats.json", "meta/tasks.parquet", "meta/episodes/chunk-000/file-000.parquet",
                "data/chunk-000/file-000.parquet"]:
        assert (dataset / rel).is_file(), rel
    assert not list(dataset.rglob(".*.tmp")) and not (dataset / "meta/.commit.json").exists()


def test_info_fields(dataset):
    info, _, _ = meta(dataset)
    assert info["codebase_version"] == "v3.0" and info["robot_type"] == "shadowhand_ur10e"
    assert info["fps"] == FPS and isinstance(info["fps"], int)
    assert (info["total_episodes"], info["total_frames"], info["total_tasks"]) == (3, 16, 2)
    assert info["chunks_size"] == 1000 and info["data_files_size_in_mb"] == 100
    assert isinstance(info["video_files_size_in_mb"], int) and info["video_path"] is None
    assert info["data_path"] == "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
    assert info["splits"] == {"train": "0:3"}
    f = info["features"]
    for key in ["timestamp", "frame_index", "episode_index", "index", "task_index"]:
        assert f[key] == {"dtype": "float32" if key == "timestamp" else "int64", "shape": [1], "names": None}
    assert f["observation.state"] == {"dtype": "float32", "shape": [S], "names": STATE_NAMES}
    assert f["action"] == {"dtype": "float32", "shape": [A], "names": ACTION_NAMES}
    assert f["observation.images.front"] == {"dtype": "image", "shape": [H, W, 3],
                                             "names": ["height", "width", "channels"]}
    assert f["next.reward"]["dtype"] == "float32" and f["next.done"]["dtype"] == f["next.success"]["dtype"] == "bool"


def test_totals_match_rows(dataset):
    assert_consistent(dataset)


def test_data_schema_and_values(dataset, episodes):
    table = read_episode_frames(dataset)
    sch = table.schema
    assert sch.field("observation.state").type == pa.list_(pa.float32(), S)
    assert sch.field("action").type == pa.list_(pa.float32(), A)
    assert sch.field("observation.images.front").type == pa.struct([("bytes", pa.binary()), ("path", pa.string())])
    for key in ["frame_index", "episode_index", "index", "task_index"]:
        assert sch.field(key).type == pa.int64()
    assert sch.field("timestamp").type == pa.float32() and sch.field("next.reward").type == pa.float32()
    assert sch.field("next.done").type == sch.field("next.success").type == pa.bool_()
    ep1 = table.filter(pc.equal(pc.field("episode_index"), 1))
    np.testing.assert_array_equal(np.array(ep1["observation.state"].to_pylist(), np.float32), episodes[1].state[:4])
    np.testing.assert_array_equal(np.array(ep1["action"].to_pylist(), np.float32), episodes[1].action)
    np.testing.assert_allclose(ep1["timestamp"].to_numpy(), np.arange(4) / FPS, rtol=1e-6)
    assert ep1["next.done"].to_pylist() == [False, False, False, True]
    assert ep1["task_index"].to_pylist() == [1] * 4
    png = ep1["observation.images.front"][2].as_py()["bytes"]
    np.testing.assert_array_equal(np.array(Image.open(io.BytesIO(png))), episodes[1].images["front"][2])


def test_tasks_parquet_pandas_index(dataset):
    tasks = pq.read_table(dataset / "meta/tasks.parquet")
    assert tasks.schema.field("task_index").type == pa.int64()
    assert dict(zip(tasks["task"].to_pylist(), tasks["task_index"].to_pylist(), strict=True)) == {
        "put the apple in the bowl": 0, "open the drawer": 1}
    pandas_meta = json.loads(tasks.schema.metadata[b"pandas"])
    assert pandas_meta["index_columns"] == ["task"]
    by_field = {c["field_name"]: c for c in pandas_meta["columns"]}
    assert by_field["task"]["name"] == "task" and by_field["task_index"]["pandas_type"] == "int64"
    assert tasks.schema.pandas_metadata == pandas_meta  # pyarrow's own parser finds it


def test_episodes_parquet(dataset):
    _, _, eps = meta(dataset)
    assert eps["episode_index"].to_pylist() == [0, 1, 2]
    assert eps["length"].to_pylist() == [7, 4, 5]
    assert eps["dataset_from_index"].to_pylist() == [0, 7, 11]
    assert eps["dataset_to_index"].to_pylist() == [7, 11, 16]
    assert eps["tasks"].to_pylist()[1] == ["open the drawer"]
    assert {"data/chunk_index", "data/file_index", "stats/action/mean", "stats/observation.images.front/std"} <= set(
        eps.column_names)


def test_stats_match_numpy(dataset, episodes):
    _, stats, eps = meta(dataset)
    state = np.concatenate([e.state[:-1] for e in episodes]).astype(np.float64)
    action = np.concatenate([e.action for e in episodes]).astype(np.float64)
    for key, x in [("observation.state", state), ("action", action)]:
        np.testing.assert_allclose(stats[key]["mean"], x.mean(0), rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(stats[key]["std"], x.std(0), rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(stats[key]["min"], x.min(0))
        np.testing.assert_allclose(stats[key]["max"], x.max(0))
        assert stats[key]["count"] == [16]
    reward = np.concatenate([e.reward for e in episodes]).astype(np.float64)
    np.testing.assert_allclose(stats["next.reward"]["mean"], [reward.mean()], rtol=1e-9)
    np.testing.assert_allclose(stats["index"]["mean"], [7.5])
    np.testing.assert_allclose(stats["index"]["max"], [15])
    imgs = np.concatenate([e.images["front"][:-1] for e in episodes]).reshape(-1, 3) / 255.0
    img = stats["observation.images.front"]
    assert np.array(img["mean"]).shape == (3, 1, 1) and img["count"] == [16]
    np.testing.assert_allclose(np.array(img["mean"]).ravel(), imgs.mean(0), rtol=1e-9)
    np.testing.assert_allclose(np.array(img["std"]).ravel(), imgs.std(0), rtol=1e-9)
    np.testing.assert_allclose(np.array(img["max"]).ravel(), imgs.max(0))
    # per-episode stats columns
    np.testing.assert_allclose(eps["stats/action/mean"].to_pylist()[1], episodes[1].action.mean(0), rtol=1e-6)
    assert eps["stats/action/count"].to_pylist() == [[7], [4], [5]]


def test_append_in_second_session(dataset, episodes):
    more = [make_episode(3, 3, instruction="open the drawer"), make_episode(6, 4, instruction="lift the can")]
    with writer(dataset) as w:
        assert (w.total_episodes, w.total_frames) == (3, 16)
        assert [w.add_episode(e) for e in more] == [3, 4]
    assert_consistent(dataset)
    info, stats, eps = meta(dataset)
    assert (info["total_episodes"], info["total_frames"], info["total_tasks"]) == (5, 25, 3)
    frames = read_episode_frames(dataset)
    assert frames.filter(pc.equal(pc.field("episode_index"), 3))["task_index"].to_pylist() == [1] * 3
    assert frames.filter(pc.equal(pc.field("episode_index"), 4))["task_index"].to_pylist() == [2] * 6
    action = np.concatenate([e.action for e in episodes + more]).astype(np.float64)
    np.testing.assert_allclose(stats["action"]["mean"], action.mean(0), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(stats["action"]["std"], action.std(0), rtol=1e-9, atol=1e-12)
    assert stats["action"]["count"] == [25]


def test_file_and_chunk_rotation(tmp_path):
    root = tmp_path / "rot"
    with writer(root, chunks_size=2, data_files_size_in_mb=1e-6) as w:
        for i in range(5):
            w.add_episode(make_episode(3, i))
    files = sorted(str(p.relative_to(root)) for p in root.glob("data/*/*.parquet"))
    assert files == ["data/chunk-000/file-000.parquet", "data/chunk-000/file-001.parquet",
                     "data/chunk-001/file-000.parquet", "data/chunk-001/file-001.parquet",
                     "data/chunk-002/file-000.parquet"]
    assert_consistent(root)
    with writer(root) as w:  # chunks_size/size limit come from the existing info.json
        w.add_episode(make_episode(2, 9))
    assert (root / "data/chunk-002/file-001.parquet").exists()
    assert_consistent(root)


def test_stray_temp_file_is_ignored_and_removed(dataset):
    stray = dataset / "data/chunk-000/.file-001.parquet.tmp"
    stray.write_bytes(b"PAR1 half written")
    assert_consistent(dataset)  # readers ignore it
    with writer(dataset) as w:
        w.add_episode(make_episode(2, 5))
    assert not stray.exists()
    assert_consistent(dataset)


def test_a_killed_add_episode_changes_nothing_and_the_writer_goes_on(dataset, monkeypatch):
    """Killed before its journal entry is complete, an episode is not in the dataset and the writer is still usable."""
    before = meta(dataset)[0]

    def die(path, data, **kw):
        raise KeyboardInterrupt("killed while journaling")

    w = writer(dataset)
    monkeypatch.setattr(lv3, "write_bytes", die)
    with pytest.raises(KeyboardInterrupt):
        w.add_episode(make_episode(4, 6))
    monkeypatch.undo()
    assert w.total_episodes == 3 and not list((dataset / lv3.PENDING_DIR).iterdir())
    assert w.add_episode(make_episode(4, 6)) == 3
    w.close()
    assert meta(dataset)[0]["total_episodes"] == 4 and meta(dataset)[0] != before
    assert not (dataset / lv3.PENDING_DIR).exists()
    assert_consistent(dataset)


def test_added_episodes_are_published_at_close_and_a_killed_writer_loses_none(dataset):
    """Until close() the visible files are the last closed dataset's (consistent and readable); the new episodes are
    journaled, and a writer opened after a kill publishes them with the same bytes as an uninterrupted writer."""
    files = {p: p.read_bytes() for p in dataset.rglob("*") if p.is_file()}
    w = writer(dataset)
    w.add_episode(make_episode(4, 6))
    w.add_episode(make_episode(3, 7))
    assert {p: p.read_bytes() for p in dataset.rglob("*") if p.is_file() and lv3.PENDING_DIR not in str(p)
            and not p.name.endswith(".tmp")} == files
    assert_consistent(dataset)
    del w  # killed: never closed
    with writer(dataset) as w2:
        assert (w2.total_episodes, w2.total_frames) == (5, 23)
    assert_consistent(dataset)
    assert not (dataset / lv3.PENDING_DIR).exists() and not list(dataset.rglob(".*.tmp"))


def test_a_writer_killed_while_closing_before_the_commit_point_leaves_the_old_dataset(dataset, monkeypatch):
    before = meta(dataset)[0]
    real = lv3._write_json

    def die_on_info(obj, path):
        if path.name == ".info.json.tmp":
            raise KeyboardInterrupt("killed while writing meta")
        real(obj, path)

    monkeypatch.setattr(lv3, "_write_json", die_on_info)
    w = writer(dataset)
    w.add_episode(make_episode(4, 6))
    with pytest.raises(KeyboardInterrupt):
        w.close()
    assert meta(dataset)[0] == before
    assert_consistent(dataset)
    monkeypatch.setattr(lv3, "_write_json", real)
    with writer(dataset) as w2:  # the journaled episode is published by the next writer
        assert w2.total_episodes == 4
    assert_consistent(dataset)


def test_crash_mid_commit_is_rolled_forward(dataset, monkeypatch):
    real = os.replace

    def die_after_data_rename(src, dst):
        if Path(dst).name == "tasks.parquet":  # journal committed, data file renamed, meta not yet
            raise KeyboardInterrupt("killed between data and meta")
        real(src, dst)

    w = writer(dataset)
    w.add_episode(make_episode(4, 7))
    monkeypatch.setattr(lerobot_files.os, "replace", die_after_data_rename)
    with pytest.raises(KeyboardInterrupt):
        w.close()
    monkeypatch.setattr(lerobot_files.os, "replace", real)
    with pytest.raises(LeRobotDatasetError, match="closed"):
        w.add_episode(make_episode(2, 8))
    assert (dataset / "meta/.commit.json").exists()
    info, _, _ = meta(dataset)
    assert (info["total_frames"], read_episode_frames(dataset).num_rows) == (16, 20)  # never claims missing rows
    with writer(dataset) as w2:  # reopening finishes the commit
        assert (w2.total_episodes, w2.total_frames) == (4, 20)
    assert not (dataset / "meta/.commit.json").exists() and not (dataset / lv3.PENDING_DIR).exists()
    assert_consistent(dataset)


def test_shape_mismatch_raises_typed_error(tmp_path):
    w = writer(tmp_path / "bad")
    with pytest.raises(EpisodeError, match=r"state has shape \(5, 4\).*only shape \(5, 5\)"):
        w.add_episode(make_episode(4, 0, s=4))
    with pytest.raises(EpisodeError, match="action"):
        w.add_episode(make_episode(4, 0, a=7))
    with pytest.raises(EpisodeError, match="no images for camera 'front'"):
        w.add_episode(make_episode(4, 0, cams=("wrist",)))
    with pytest.raises(EpisodeError, match="fps"):
        w.add_episode(make_episode(4, 0, fps=10))
    assert not list((tmp_path / "bad").glob("data/*/*.parquet"))


def test_incompatible_resume_raises(dataset):
    with pytest.raises(LeRobotDatasetError, match="observation.state"):
        writer(dataset, state_names=STATE_NAMES + ["extra"])


def test_no_cameras(tmp_path):
    root = tmp_path / "nocam"
    with writer(root, cameras=None) as w:
        w.add_episode(make_episode(3, 0))
    assert not any(k.startswith("observation.images") for k in meta(root)[0]["features"])
    assert_consistent(root)


def test_dataset_card(dataset):
    info, _, _ = meta(dataset)
    path = write_dataset_card(dataset, task_id="GenDex/PutAppleBowl-v0", instruction="put the apple in the bowl",
                              robot="ShadowHand on UR10e",
                              env_kwargs={"control_mode": "pd_joint_pos", "control_joint": "both", "obs_mode": "state"},
                              n_episodes=info["total_episodes"], n_frames=info["total_frames"],
                              how_made="Scripted grasp solver, successful rollouts only.")
    text = path.read_text()
    front = yaml.safe_load(text.split("---")[1])
    assert front["license"] == "apache-2.0" and front["task_categories"] == ["robotics"]
    assert {"LeRobot", "gendex", "shadowhand"} <= set(front["tags"])
    assert "pd_joint_pos" in text and "Scripted grasp solver" in text and '"codebase_version": "v3.0"' in text
    assert ("gym.make('GenDex/PutAppleBowl-v0', control_mode='pd_joint_pos', control_joint='both', "
            "obs_mode='state')") in text  # the exact env the actions belong to


def _smooth_episode(t: int, seed: int, h: int = 16, w: int = 24) -> Episode:
    ep = make_episode(t, seed, cams=())
    yy, xx = np.mgrid[0:h, 0:w]
    frames = np.stack([np.stack([(xx * 8 + 10 * k) % 256, (yy * 12) % 256, np.full_like(xx, 40 * seed % 256)], -1)
                       for k in range(t + 1)]).astype(np.uint8)
    ep.images = {"front": frames}
    return ep


@pytest.mark.parametrize("codec", ["libsvtav1", "libx264"])
def test_camera_images_as_video_files_in_the_v3_layout(tmp_path, codec):
    """With a video codec, camera frames go to videos/<key>/chunk-000/file-000.mp4, episode after episode (frame k of
    an episode at from_timestamp + k/fps), the feature is declared as video, the episode rows say where each
    episode's frames are, and the same episodes give the same bytes, also when the writer was closed and reopened
    or killed between episodes."""
    from gendex_envs.video import decode

    eps = [_smooth_episode(6, 1), _smooth_episode(4, 2), _smooth_episode(5, 3)]
    roots = [tmp_path / "a", tmp_path / "b", tmp_path / "c"]

    def open_writer(root):
        return writer(root, cameras={"front": (16, 24)}, video_codec=codec)

    with open_writer(roots[0]) as w:
        for e in eps:
            w.add_episode(e)
    with open_writer(roots[1]) as w:
        w.add_episode(eps[0])
    with open_writer(roots[1]) as w:
        for e in eps[1:]:
            w.add_episode(e)
    w = open_writer(roots[2])
    w.add_episode(eps[0])
    w.add_episode(eps[1])
    del w  # killed
    with open_writer(roots[2]) as w:
        w.add_episode(eps[2])
    info, stats, rows = meta(roots[0])
    key = "observation.images.front"
    assert info["video_path"] == lv3.VIDEO_PATH and info["features"][key]["dtype"] == "video"
    assert info["features"][key]["info"]["video.codec"] == {"libsvtav1": "av1", "libx264": "h264"}[codec]
    assert key not in read_episode_frames(roots[0]).column_names  # not inside the parquet
    assert np.asarray(stats[key]["mean"]).shape == (3, 1, 1)
    path = roots[0] / "videos" / key / "chunk-000/file-000.mp4"
    assert [p.name for p in path.parent.iterdir()] == ["file-000.mp4"]
    frames, start = decode(path), 0
    assert len(frames) == sum(e.length for e in eps)  # T frames per episode: one per action, like the parquet rows
    for e, row in zip(eps, rows.to_pylist(), strict=True):
        assert (row[f"videos/{key}/chunk_index"], row[f"videos/{key}/file_index"]) == (0, 0)
        assert row[f"videos/{key}/from_timestamp"] == start / FPS
        assert row[f"videos/{key}/to_timestamp"] == (start + e.length) / FPS
        assert np.abs(frames[start:start + e.length].astype(int) - e.images["front"][:e.length]).mean() < 12
        start += e.length
    for root in roots[1:]:
        files = sorted(p.relative_to(roots[0]) for p in roots[0].rglob("*") if p.is_file())
        assert files == sorted(p.relative_to(root) for p in root.rglob("*") if p.is_file())
        for f in files:
            assert (roots[0] / f).read_bytes() == (root / f).read_bytes(), (root, f)


def test_video_files_are_split_at_the_size_limit(tmp_path):
    """A new video file (then a new chunk after chunks_size files) is started when the next episode would pass
    video_files_size_in_mb; each episode's frames are in one file."""
    from gendex_envs.video import decode

    root = tmp_path / "split"
    eps = [_smooth_episode(4, s) for s in range(5)]
    with writer(root, cameras={"front": (16, 24)}, video_codec="libx264", chunks_size=2,
                video_files_size_in_mb=2e-3) as w:  # about two episodes per file
        for e in eps:
            w.add_episode(e)
    info, _, rows = meta(root)
    assert info["video_files_size_in_mb"] == 2e-3
    key = "observation.images.front"
    where = [(r[f"videos/{key}/chunk_index"], r[f"videos/{key}/file_index"]) for r in rows.to_pylist()]
    assert where[0] == (0, 0) and where[-1] > (0, 1) and len(set(where)) < len(where)
    for (chunk, file) in sorted(set(where)):
        here = [r for r, w in zip(rows.to_pylist(), where, strict=True) if w == (chunk, file)]
        frames = decode(root / lv3.VIDEO_PATH.format(video_key=key, chunk_index=chunk, file_index=file))
        assert len(frames) == sum(r["length"] for r in here) == round(here[-1][f"videos/{key}/to_timestamp"] * FPS)
        assert here[0][f"videos/{key}/from_timestamp"] == 0.0
    assert_consistent(root)


def test_the_encoder_never_sees_uninitialised_row_padding(tmp_path):
    """FFmpeg pads each plane's rows to an aligned stride and leaves the padding uninitialised; x264 reads it, which
    made a 24-pixel-wide video's bytes differ about once in 300 encodes (a CI failure of the test above). The frames
    handed to the encoder have zeroed padding, so repeated encodes give one set of bytes."""
    from gendex_envs.video import PIX_FMT, _yuv_frame, encode

    rgb = _smooth_episode(6, 1).images["front"]
    frame = _yuv_frame(rgb[0])
    assert frame.format.name == PIX_FMT
    padded = [p for p in frame.planes if p.line_size > p.width]
    assert padded  # 24 px rows (12 px chroma) are padded to the stride: the case that mattered
    for plane in padded:
        rows = np.frombuffer(memoryview(plane), dtype=np.uint8).reshape(-1, plane.line_size)
        assert not rows[:, plane.width:].any()
    digests = set()
    for _ in range(100):
        encode(rgb, tmp_path / "v.mp4", FPS, "libx264")
        digests.add(hashlib.sha256((tmp_path / "v.mp4").read_bytes()).hexdigest())
    assert len(digests) == 1


def test_x264_keeps_to_avx2_on_avx512_cpus_and_its_bytes_do_not_change(tmp_path, monkeypatch):
    """x264's AVX-512 kernels made identical input encode to different bytes now and then on a loaded machine (the
    test above failed in CI; benchmarks/results/video.md): on a CPU with AVX-512 x264 is kept to AVX2, which gives
    the bytes the AVX-512 kernels give when they do not stray, so checksums recorded before stay valid."""
    import gendex_envs.video as video

    avx512 = video._cpu_has_avx512()
    assert "x264-params" not in video._encoder_options("libsvtav1")
    monkeypatch.setattr(video, "_cpu_has_avx512", lambda: False)
    assert "x264-params" not in video._encoder_options("libx264")
    if not avx512:  # both kernel sets exist only on an AVX-512 CPU
        return
    rgb = _smooth_episode(6, 1).images["front"]
    frames = np.random.default_rng(0).integers(0, 256, (8, 32, 48, 3), dtype=np.uint8)
    digests = []
    for restrict in (False, True):
        monkeypatch.setattr(video, "_cpu_has_avx512", lambda r=restrict: r)
        for name, x in (("ramp", rgb), ("noise", frames)):
            video.encode(x, tmp_path / f"{name}.mp4", FPS, "libx264")
        digests.append([hashlib.sha256((tmp_path / f"{n}.mp4").read_bytes()).digest() for n in ("ramp", "noise")])
    assert video._encoder_options("libx264")["x264-params"] == "asm=AVX2"
    assert digests[0] == digests[1]


def test_video_options_are_checked(tmp_path):
    from gendex_envs.video import VideoError, encode

    with pytest.raises(LeRobotDatasetError, match="video_codec 'mjpeg' is not one of"):
        writer(tmp_path / "x", video_codec="mjpeg")
    with pytest.raises(VideoError, match="even height and width"):
        encode(np.zeros((2, 7, 8, 3), np.uint8), tmp_path / "odd.mp4", 10)
    with pytest.raises(VideoError, match=r"\[T, H, W, 3\] uint8"):
        encode(np.zeros((2, 8, 8), np.uint8), tmp_path / "flat.mp4", 10)


def test_a_resumed_writer_writes_the_same_bytes_as_an_uninterrupted_one(tmp_path, episodes):
    """Reading a data file back gives parquet's list naming; the writer normalizes it, so a collection stopped after
    its first episode and resumed ends with the same files as one that never stopped."""
    with writer(tmp_path / "once") as w:
        for e in episodes:
            w.add_episode(e)
    with writer(tmp_path / "resumed") as w:
        w.add_episode(episodes[0])
    with writer(tmp_path / "resumed") as w:
        for e in episodes[1:]:
            w.add_episode(e)
    files = sorted(p.relative_to(tmp_path / "once") for p in (tmp_path / "once").rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(tmp_path / "resumed") for p in (tmp_path / "resumed").rglob("*")
                           if p.is_file())
    for f in files:
        assert (tmp_path / "once" / f).read_bytes() == (tmp_path / "resumed" / f).read_bytes(), f


def test_a_long_collection_resumed_midway_writes_the_same_bytes_as_an_uninterrupted_one(tmp_path):
    """At the size of a real dataset two more things showed (a 200-episode PutAppleBowl build killed after 70
    episodes and resumed): the stats rounded differently (one flat merge against one episode at a time), and the data
    parquet's state column compressed differently (the encoder's dictionary falls back to plain when it outgrows its
    page, and where it does followed how the table was chunked). 30 episodes of 800 frames with 60 state values pass
    that size."""
    names = [f"q{i}" for i in range(60)]
    eps = [make_episode(800, seed, cams=(), s=60) for seed in range(30)]

    def open_writer(root):
        return writer(root, state_names=names, cameras={})

    with open_writer(tmp_path / "once") as w:
        for e in eps:
            w.add_episode(e)
    w = open_writer(tmp_path / "resumed")
    for e in eps[:11]:
        w.add_episode(e)
    del w  # killed: never closed
    with open_writer(tmp_path / "resumed") as w:
        for e in eps[11:]:
            w.add_episode(e)
    files = sorted(p.relative_to(tmp_path / "once") for p in (tmp_path / "once").rglob("*") if p.is_file())
    for f in files:
        assert (tmp_path / "once" / f).read_bytes() == (tmp_path / "resumed" / f).read_bytes(), f
