"""gendex_envs.video.encode: a video FFmpeg fails to write is encoded again from the start, to the same bytes; a
video that keeps failing is a VideoError naming the file."""

from __future__ import annotations

import av
import numpy as np
import pytest

from gendex_envs import video


def _frames(t: int = 24) -> np.ndarray:
    rng = np.random.default_rng(0)
    return rng.integers(0, 255, (t, 32, 32, 3), dtype=np.uint8)


def test_a_failed_encode_is_encoded_again_to_the_same_bytes(tmp_path, monkeypatch):
    frames = _frames()
    video.encode(frames, tmp_path / "once.mp4", 20)
    real, calls = video._encode, []

    def flaky(frames, path, fps, codec):
        calls.append(path)
        if len(calls) == 1:  # as the muxer refused a flushed packet: a partial file is left behind
            real(frames[:3], path, fps, codec)
            raise av.error.ArgumentError(22, "Invalid argument", str(path))
        return real(frames, path, fps, codec)

    monkeypatch.setattr(video, "_encode", flaky)
    video.encode(frames, tmp_path / "again.mp4", 20)
    assert len(calls) == 2
    assert (tmp_path / "again.mp4").read_bytes() == (tmp_path / "once.mp4").read_bytes()
    np.testing.assert_array_equal(video.decode(tmp_path / "again.mp4").shape, frames.shape)


def test_an_encode_that_keeps_failing_is_a_video_error_and_leaves_no_file(tmp_path, monkeypatch):
    def broken(frames, path, fps, codec):
        path.write_bytes(b"partial")
        raise av.error.ArgumentError(22, "Invalid argument", str(path))

    monkeypatch.setattr(video, "_encode", broken)
    with pytest.raises(video.VideoError, match=f"bad.mp4: FFmpeg failed to encode 24 frames {video.ENCODE_TRIES} "):
        video.encode(_frames(), tmp_path / "bad.mp4", 20)
    assert not (tmp_path / "bad.mp4").exists()
    with pytest.raises(video.VideoError, match="not one of"):  # bad input is refused at once, not retried
        video.encode(_frames(), tmp_path / "x.mp4", 20, codec="mpeg2")


def test_a_hung_encoder_is_left_behind_and_a_fresh_one_writes_the_same_bytes(tmp_path, monkeypatch):
    """As SVT-AV1 once blocked for good inside svt_av1_enc_send_picture: the first run opens its file, writes a
    little and never returns while encode waits; a fresh run gives the file, and the first one, let go afterwards,
    changes nothing in the folder."""
    import threading

    frames = _frames()
    video.encode(frames, tmp_path / "once.mp4", 20)
    real, calls, release = video._encode, [], threading.Event()
    out = tmp_path / "out"
    out.mkdir()

    def hangs_once(frames, path, fps, codec):
        calls.append(path)
        if len(calls) == 1:
            with open(path, "wb") as f:
                f.write(b"partial")
                release.wait(30)
                f.write(b"late bytes")
            return None
        return real(frames, path, fps, codec)

    monkeypatch.setattr(video, "_encode", hangs_once)
    monkeypatch.setattr(video, "ENCODE_TIMEOUT_S", 0.5)
    video.encode(frames, out / "again.mp4", 20)
    assert len(calls) == 2 and calls[0] != calls[1]  # each run writes its own file
    release.set()
    for t in [t for t in threading.enumerate() if t.name.startswith("encode ")]:
        t.join(5)
    assert [p.name for p in out.iterdir()] == ["again.mp4"]
    assert (out / "again.mp4").read_bytes() == (tmp_path / "once.mp4").read_bytes()


def test_an_encoder_that_always_hangs_is_a_video_error_naming_the_file(tmp_path, monkeypatch):
    import threading

    release = threading.Event()
    monkeypatch.setattr(video, "_encode", lambda frames, path, fps, codec: release.wait(30))
    monkeypatch.setattr(video, "ENCODE_TIMEOUT_S", 0.2)
    with pytest.raises(video.VideoError, match=r"stuck.mp4: .*did not finish 24 frames in 0.2 s"):
        video.encode(_frames(), tmp_path / "stuck.mp4", 20)
    release.set()
    assert list(tmp_path.iterdir()) == []


def test_an_error_that_is_not_ffmpegs_is_raised_at_once_and_leaves_no_part_file(tmp_path, monkeypatch):
    calls = []

    def full_disk(frames, path, fps, codec):
        calls.append(path)
        path.write_bytes(b"partial")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(video, "_encode", full_disk)
    with pytest.raises(OSError, match="No space left"):
        video.encode(_frames(), tmp_path / "full.mp4", 20)
    assert len(calls) == 1 and list(tmp_path.iterdir()) == []
