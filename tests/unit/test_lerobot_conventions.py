"""The writer's ``conventions``: 1 writes the stats the published datasets hold (pinned byte for byte), 2 lerobot
0.4's, with the quantiles q01/q10/q50/q90/q99 pi0.5 normalises by, 3 those with the dataset's quantiles over all its
frames; resume and replay keep the bytes in each; and
lerobot 0.4's video layout (one file per camera, episodes remuxed into it), which both conventions write."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from test_lerobot_v3 import FPS, _smooth_episode, assert_consistent, make_episode, meta, writer

from gendex.data import lerobot_v3 as lv3
from gendex.data.lerobot_files import QUANTILES, STAT_NAMES, pool_quantiles, stat_names
from gendex.data.lerobot_v3 import LeRobotDatasetError

Q_NAMES = ["q01", "q10", "q50", "q90", "q99"]
NUMERIC = ["observation.state", "action", "next.reward", "next.success", "next.done", "timestamp", "frame_index",
           "episode_index", "index", "task_index"]


def _episodes(t: tuple[int, ...] = (7, 4, 5)):
    return [make_episode(t[0], 0), make_episode(t[1], 1, instruction="open the drawer"), make_episode(t[2], 2)]


def _write(root: Path, eps, **kw) -> Path:
    with writer(root, **kw) as w:
        for e in eps:
            w.add_episode(e)
    return root


def _files(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


def test_the_quantile_names_are_lerobots():
    assert list(QUANTILES) == [f"q{int(q * 100):02d}" for q in [0.01, 0.10, 0.50, 0.90, 0.99]] == Q_NAMES
    assert stat_names(1) == STAT_NAMES == ("min", "max", "mean", "std", "count")
    assert stat_names(2) == stat_names(3) == (*STAT_NAMES, *Q_NAMES)


def test_conventions_1_is_the_default_and_writes_the_published_stats_byte_for_byte(tmp_path):
    """The digests were taken from the writer before conventions existed (commit b3080255) on these episodes: the
    published manifests' stats.json and episodes parquet rows come from this code path."""
    root = _write(tmp_path / "ds", _episodes())
    _, stats, eps = meta(root)
    assert all(list(d) == list(STAT_NAMES) for d in stats.values()) and len(stats) == 11
    assert sorted(c for c in eps.column_names if c.startswith("stats/")) == sorted(
        f"stats/{k}/{s}" for k in stats for s in STAT_NAMES)
    assert hashlib.sha256((root / "meta/stats.json").read_bytes()).hexdigest() == \
        "80834b40542cae02983af6162c1fac7030ec8d04133ca2c417d53a09142b8bb5"
    assert hashlib.sha256(json.dumps(eps.to_pylist()).encode()).hexdigest() == \
        "8a4bb3eb0e272786ea354cdb4fdcc4fdb7c56b4a6e658632a8ad73395c66f3f2"
    assert _files(root) == _files(_write(tmp_path / "explicit", _episodes(), conventions=1))


def test_conventions_2_holds_each_episodes_exact_quantiles_and_their_count_weighted_mean(tmp_path):
    episodes = _episodes()
    root = _write(tmp_path / "ds", episodes, conventions=2)
    _, stats, eps = meta(root)
    assert all(list(d) == [*STAT_NAMES, *Q_NAMES] for d in stats.values())
    rows = eps.to_pylist()
    counts = np.array([e.length for e in episodes], float)
    for key, per_episode in [("observation.state", [e.state[:-1] for e in episodes]),
                             ("action", [e.action for e in episodes]),
                             ("next.reward", [e.reward[:, None] for e in episodes])]:
        for q, level in QUANTILES.items():
            want = [np.quantile(x.astype(np.float64), level, axis=0) for x in per_episode]
            for row, w in zip(rows, want, strict=True):
                np.testing.assert_array_equal(row[f"stats/{key}/{q}"], w)
            np.testing.assert_allclose(stats[key][q], (np.stack(want) * counts[:, None]).sum(0) / counts.sum(),
                                       rtol=1e-12)
    # images: per channel over every pixel of the episode's frames, scaled to [0, 1], shaped [3, 1, 1]
    for row, e in zip(rows, episodes, strict=True):
        pixels = e.images["front"][:-1].reshape(-1, 3)
        for q, level in QUANTILES.items():
            got = np.asarray(row[f"stats/observation.images.front/{q}"])
            assert got.shape == (3, 1, 1)
            np.testing.assert_array_equal(got.ravel(), np.quantile(pixels, level, axis=0) / 255.0)
    assert np.asarray(stats["observation.images.front"]["q50"]).shape == (3, 1, 1)
    for key, d in stats.items():  # ordered as quantiles are, inside min..max
        ordered = [np.asarray(d[s]) for s in ["min", *Q_NAMES, "max"]]
        assert all(np.all(a <= b + 1e-12) for a, b in zip(ordered, ordered[1:], strict=False)), key
    # the rest is conventions 1's, value for value
    _, stats1, _ = meta(_write(tmp_path / "one", episodes))
    assert {k: {s: d[s] for s in STAT_NAMES} for k, d in stats.items()} == stats1
    assert_consistent(root)


def test_pi05_quantile_normalisation_of_the_written_stats_is_finite_and_spans_minus_one_to_one(tmp_path):
    """What lerobot's NormalizerProcessorStep does with NormalizationMode.QUANTILES (pi0.5's mode for state and
    action): 2 (x - q01) / (q99 - q01) - 1, a zero width replaced by eps; and back."""
    episodes = [make_episode(60, s) for s in range(4)]
    root = _write(tmp_path / "ds", episodes, conventions=2)
    stats = json.loads((root / "meta/stats.json").read_text())
    frames = lv3.read_episode_frames(root)
    eps = 1e-8
    for key in NUMERIC:
        q01, q50, q99 = (np.asarray(stats[key][q], np.float64) for q in ("q01", "q50", "q99"))
        assert np.all(np.isfinite([q01, q50, q99])) and np.all(q01 <= q50) and np.all(q50 <= q99), key
        x = np.asarray(frames[key].to_pylist(), np.float64).reshape(frames.num_rows, -1)
        width = np.where(q99 - q01 == 0, eps, q99 - q01)
        y = 2 * (x - q01) / width - 1
        assert np.all(np.isfinite(y)), key
        np.testing.assert_allclose((y + 1) * width / 2 + q01, x, atol=1e-9)
        if key in ("observation.state", "action"):
            assert np.all(np.abs(2 * (q50 - q01) / width - 1) <= 1)
            inside = np.mean(np.abs(y) <= 1, axis=0)
            assert np.all(inside >= 0.9), (key, inside)  # 1 % to 99 % per episode: most frames within [-1, 1]
            assert np.all(np.abs(y).max(0) < 1.5), key


def test_conventions_3_pools_the_quantiles_over_every_frame(tmp_path):
    """A value constant within each episode but not between them (which fingers a grasp curls): lerobot's mean of the
    episodes' quantiles (conventions 2) gives q01 == q99 inside a wider min..max, and pi0.5's normalisation turns a
    frame into ~1e8; the dataset's own quantiles (conventions 3) keep it within [-1, 1]. Nothing else differs."""
    episodes = []
    for seed, curl in enumerate([0.0, 0.0, 0.0, 1.4, 0.0]):
        ep = make_episode(20 + seed, seed)
        ep.action[:, 1] = curl
        episodes.append(ep)
    two, three = (_write(tmp_path / f"c{c}", episodes, conventions=c) for c in (2, 3))
    _, stats2, rows2 = meta(two)
    _, stats3, rows3 = meta(three)
    assert rows3.to_pylist() == rows2.to_pylist()  # each episode's own quantiles, as lerobot writes them
    frames = lv3.read_episode_frames(three)
    for key in NUMERIC:
        x = np.asarray(frames[key].to_pylist(), np.float64).reshape(frames.num_rows, -1)
        for q, level in QUANTILES.items():
            np.testing.assert_array_equal(stats3[key][q], np.quantile(x, level, axis=0), err_msg=f"{key} {q}")
        assert {s: stats3[key][s] for s in STAT_NAMES} == {s: stats2[key][s] for s in STAT_NAMES}
    assert stats3["observation.images.front"] == stats2["observation.images.front"]  # images: as lerobot's

    def pi05(stats, x):
        q01, q99 = np.asarray(stats["action"]["q01"]), np.asarray(stats["action"]["q99"])
        return 2 * (x - q01) / np.where(q99 - q01 == 0, 1e-8, q99 - q01) - 1

    curled = episodes[3].action[0].astype(np.float64)
    assert stats2["action"]["q01"][1] == stats2["action"]["q99"][1] < stats2["action"]["max"][1]
    assert abs(pi05(stats2, curled)[1]) > 1e6
    assert stats3["action"]["q01"][1] == 0.0 and stats3["action"]["q99"][1] == pytest.approx(1.4)
    y = pi05(stats3, np.asarray(frames["action"].to_pylist(), np.float64))
    assert np.all(np.abs(y[:, 1]) <= 1.0 + 1e-6) and np.abs(y).max() < 1.5  # beyond q01..q99: the tails only
    # a published conventions-2 dataset pooled afterwards: conventions 3's bytes, every file
    pool_quantiles(two)
    assert _files(two) == _files(three)
    with pytest.raises(LeRobotDatasetError, match=r"no quantiles for \['observation.state'.*conventions 2 or 3"):
        pool_quantiles(_write(tmp_path / "c1", episodes[:1]))
    (two / "data/chunk-000/file-000.parquet").write_bytes(b"PAR1 not parquet")
    with pytest.raises(LeRobotDatasetError, match=r"file-000.parquet: not a data file with the columns"):
        pool_quantiles(two)
    for info, stats in [("[]", "{}"), ('{"features": {"a": {"dtype": "float32"}}}', '"x"'), ("{", "{}")]:
        bad = tmp_path / "bad" / "meta"
        bad.mkdir(parents=True, exist_ok=True)
        (bad / "info.json").write_text(info)
        (bad / "stats.json").write_text(stats)
        with pytest.raises(LeRobotDatasetError, match=r"not a published LeRobot v3.0 dataset"):
            pool_quantiles(bad.parent)
        assert (bad / "stats.json").read_text() == stats  # nothing rewritten


@pytest.mark.parametrize("conventions", [2, 3])
@pytest.mark.parametrize("codec", [None, "libx264"])
def test_conventions_with_quantiles_resumed_or_killed_write_the_same_bytes(tmp_path, codec, conventions):
    """Closed and reopened, or killed with journaled episodes and replayed: the same files as one session (the
    per-episode quantiles come back from the episodes parquet and from the journal)."""
    eps = [_smooth_episode(6, 1), _smooth_episode(4, 2), _smooth_episode(5, 3)]

    def open_writer(root):
        return writer(root, cameras={"front": (16, 24)}, video_codec=codec, conventions=conventions)

    roots = [tmp_path / "once", tmp_path / "reopened", tmp_path / "killed"]
    with open_writer(roots[0]) as w:
        for e in eps:
            w.add_episode(e)
    with open_writer(roots[1]) as w:
        w.add_episode(eps[0])
    with open_writer(roots[1]) as w:
        for e in eps[1:]:
            w.add_episode(e)
    with open_writer(roots[2]) as w:
        w.add_episode(eps[0])
    w = open_writer(roots[2])
    w.add_episode(eps[1])
    w.add_episode(eps[2])
    assert len(list((roots[2] / lv3.PENDING_DIR).glob("*.arrow"))) == 2
    del w  # killed: never closed
    with open_writer(roots[2]) as w:
        assert w.total_episodes == 3
    assert "q99" in meta(roots[0])[1]["observation.images.front"]
    for root in roots[1:]:
        assert _files(root) == _files(roots[0]), root


def test_a_root_is_appended_to_only_with_the_conventions_it_was_written_with(tmp_path):
    one = _write(tmp_path / "one", _episodes()[:1])
    with pytest.raises(LeRobotDatasetError, match=r"holds the stats min, max, mean, std, count \(conventions 1\); "
                                                  r"this writer has conventions 2 \(.*q01.*\): append only with the "
                                                  r"conventions the dataset was written with"):
        writer(one, conventions=2)
    two = _write(tmp_path / "two", _episodes()[:1], conventions=2)
    with pytest.raises(LeRobotDatasetError, match=r"\(conventions 2\); this writer has conventions 1"):
        writer(two)
    # killed before its first close: only the journal says which conventions the episode was written with
    w = writer(tmp_path / "journal", conventions=2)
    w.add_episode(make_episode(3, 0))
    del w
    with pytest.raises(LeRobotDatasetError, match=r"journal entry episode-000000.arrow holds the stats"):
        writer(tmp_path / "journal")
    with writer(tmp_path / "journal", conventions=2) as w:
        assert w.total_episodes == 1
    assert list(pq.read_table(tmp_path / "journal/meta/episodes/chunk-000/file-000.parquet").column_names).count(
        "stats/action/q01") == 1


@pytest.mark.parametrize("value", [0, 4, True, "2", 2.0, None])
def test_conventions_must_be_1_2_or_3(tmp_path, value):
    with pytest.raises(LeRobotDatasetError, match=rf"conventions {value!r} is not one of \[1, 2, 3\]"):
        writer(tmp_path / "x", conventions=value)
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize("conventions", [1, 2])
def test_video_frames_are_remuxed_not_reencoded_and_found_at_their_timestamps(tmp_path, conventions):
    """lerobot 0.4's video layout under both conventions: one file per camera, episode after episode; frame i of an
    episode decodes at from_timestamp + i / fps (lerobot matches timestamps within 1e-4 s) to exactly the pixels of
    that episode's own encoded video (its packets are copied, not encoded again)."""
    import av

    from gendex_envs.video import encode

    def decoded(path: Path) -> list[tuple[float, np.ndarray]]:
        with av.open(str(path)) as c:
            return [(f.time, f.to_ndarray(format="rgb24")) for f in c.decode(video=0)]

    eps = [_smooth_episode(6, 1), _smooth_episode(4, 2), _smooth_episode(5, 3)]
    root = _write(tmp_path / "ds", eps, cameras={"front": (16, 24)}, video_codec="libx264", conventions=conventions)
    key = "observation.images.front"
    assert [str(p.relative_to(root)) for p in root.rglob("*.mp4")] == [f"videos/{key}/chunk-000/file-000.mp4"]
    frames = decoded(root / f"videos/{key}/chunk-000/file-000.mp4")
    by_time = {round(t * FPS): (t, img) for t, img in frames}
    assert len(by_time) == len(frames) == sum(e.length for e in eps)
    for e, row in zip(eps, meta(root)[2].to_pylist(), strict=True):
        encode(e.images["front"][:e.length], tmp_path / "own.mp4", FPS, "libx264")
        own = decoded(tmp_path / "own.mp4")
        start = row[f"videos/{key}/from_timestamp"]
        assert row[f"videos/{key}/to_timestamp"] == start + e.length / FPS
        for i in range(e.length):
            t, img = by_time[round((start + i / FPS) * FPS)]
            assert abs(t - (start + i / FPS)) < 1e-4
            np.testing.assert_array_equal(img, own[i][1])
