"""Frames as video files (PyAV, FFmpeg's libraries): the camera streams of LeRobot v3.0 datasets, the episode
videos of evaluations.

:func:`encode` writes ``[T, H, W, 3]`` uint8 RGB frames as an MP4 whose frame ``i`` has presentation time ``i / fps``
exactly (time base ``1/fps``), so lerobot's decoder finds each frame at its timestamp. The default codec is
lerobot's own default, AV1 by SVT-AV1 (``libsvtav1``, yuv420p, a key frame every 2 frames, CRF 30); ``libx264``
(H.264) is the alternative for players without AV1. Encoding is deterministic: the same frames give the same bytes
(a dataset build can be verified against its manifest's checksums; :func:`_encoder_options` says what that
takes for x264). :func:`decode` reads every frame back.
"""

from __future__ import annotations

import functools
import logging
import os
import threading
from pathlib import Path

import numpy as np

from gendex_envs.atomic_io import atomic_path
from gendex_envs.errors import GenDexError

log = logging.getLogger(__name__)

CODECS = {"libsvtav1": ("av1", {"g": "2", "crf": "30"}), "libx264": ("h264", {"g": "2", "crf": "23"})}
"""Encoder -> (codec name recorded in the dataset's features, encoder options)."""
DEFAULT_CODEC = "libsvtav1"
PIX_FMT = "yuv420p"


class VideoError(GenDexError, ValueError):
    """Frames cannot be encoded as asked, or a video file cannot be read."""


ENCODE_TRIES = 3
"""Times :func:`encode` runs FFmpeg on one video before it gives up."""
ENCODE_TIMEOUT_S = 120.0
"""Seconds one run of the encoder may take before :func:`encode` counts it as hung and runs it again. A 96 px episode
encodes in well under a second; SVT-AV1 once blocked for good inside ``svt_av1_enc_send_picture`` with every thread
idle (twice in one dataset build of 52 tasks under full CPU load; a known class of SVT-AV1 deadlock)."""


class EncoderHung(VideoError):
    """One run of the encoder did not finish within :data:`ENCODE_TIMEOUT_S`."""


def encode(frames: np.ndarray, path: Path | str, fps: int, codec: str = DEFAULT_CODEC) -> None:
    """Write ``frames`` ([T, H, W, 3] uint8 RGB; H and W even) to the MP4 file ``path``.

    The MP4 muxer once refused a packet SVT-AV1 flushed at the end of an episode (``Invalid argument``, errno 22;
    one video in about 170 of a dataset build under full CPU load; 150 encodes of the same sizes beside the build
    did not repeat it). The same frames encode again from the start, up to :data:`ENCODE_TRIES` times, and give the
    same bytes (the encoding is deterministic); a :class:`VideoError` names the last failure. An encoder that hangs
    (:data:`ENCODE_TIMEOUT_S`) is left behind and the frames are encoded again by a fresh one. Each run writes its own
    hidden file beside ``path`` and only a finished one is renamed to ``path``, so a run left behind never touches the
    result, and nothing half-written is left at ``path``."""
    import av

    if codec not in CODECS:
        raise VideoError(f"video codec {codec!r} is not one of {sorted(CODECS)}")
    frames = np.asarray(frames)
    if frames.ndim != 4 or frames.shape[-1] != 3 or frames.dtype != np.uint8 or len(frames) == 0:
        raise VideoError(f"frames must be [T, H, W, 3] uint8 with T >= 1, got {frames.dtype} {list(frames.shape)}")
    h, w = frames.shape[1:3]
    if h % 2 or w % 2:
        raise VideoError(f"frames of {h} x {w}: {PIX_FMT} video needs an even height and width")
    path = Path(path)
    for attempt in range(1, ENCODE_TRIES + 1):
        try:
            # atomic_path removes the run's file on any error (a hung run that holds it open writes on into the
            # unlinked file) and renames only a finished one into place
            with atomic_path(path) as part:
                _encode_watched(frames, part, fps, codec)
            return None
        except (av.error.FFmpegError, EncoderHung) as exc:
            if attempt == ENCODE_TRIES:
                raise VideoError(f"{path}: FFmpeg failed to encode {len(frames)} frames {ENCODE_TRIES} times "
                                 f"({exc})") from exc
            log.warning("%s: FFmpeg failed to encode (%s); encoding it again (try %d of %d)", path, exc,
                        attempt + 1, ENCODE_TRIES)
        # anything else (a full disk, an interrupt) is not worth another try and propagates at once
    return None


def _encode_watched(frames: np.ndarray, path: Path, fps: int, codec: str) -> None:
    """:func:`_encode` on a daemon thread (PyAV releases the GIL inside FFmpeg), given up after
    :data:`ENCODE_TIMEOUT_S` as :class:`EncoderHung`; the thread is abandoned (it sleeps, holding no CPU)."""
    failure: list[BaseException] = []

    def run() -> None:
        try:
            _encode(frames, path, fps, codec)
        except BaseException as exc:  # handed to the caller's thread
            failure.append(exc)

    worker = threading.Thread(target=run, name=f"encode {path.name}", daemon=True)
    worker.start()
    worker.join(ENCODE_TIMEOUT_S)
    if worker.is_alive():
        raise EncoderHung(f"the encoder did not finish {len(frames)} frames in {ENCODE_TIMEOUT_S:g} s")
    if failure:
        raise failure[0]


def _encode(frames: np.ndarray, path: Path | str, fps: int, codec: str) -> None:
    """One run of FFmpeg's encoder and muxer over ``frames`` (checked by :func:`encode`)."""
    import av

    h, w = frames.shape[1:3]
    os.environ.setdefault("SVT_LOG", "1")  # SVT-AV1 prints its whole configuration at info level
    with av.open(str(path), "w", format="mp4") as container:
        stream = container.add_stream(codec, rate=int(fps))
        stream.width, stream.height, stream.pix_fmt = w, h, PIX_FMT
        stream.options = _encoder_options(codec)
        for frame in frames:
            for packet in stream.encode(_yuv_frame(frame)):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)


def _encoder_options(codec: str) -> dict[str, str]:
    """The encoder options of ``codec``; on a CPU with AVX-512, x264 is kept to its AVX2 kernels.

    With its AVX-512 kernels, x264 (one thread, the same options and the same input planes, padding included) encoded
    the same frames to different bytes about once in 850 encodes while the machine was under CPU load, and not once
    in 3 150 restricted to AVX2 (records in ``benchmarks/results/video.md``). The two give the same bytes whenever the
    AVX-512 run does not stray, so the restriction changes no checksum. Every AVX-512 CPU has AVX2, so the
    restriction never names an instruction set the CPU lacks."""
    options = dict(CODECS[codec][1])
    if codec == "libx264" and _cpu_has_avx512():
        options["x264-params"] = "asm=AVX2"
    return options


@functools.cache
def _cpu_has_avx512() -> bool:
    """Whether the CPU reports AVX-512 Foundation (Linux; elsewhere assumed not)."""
    from gendex_envs.blas import cpu_flags

    return "avx512f" in cpu_flags()


def _yuv_frame(rgb: np.ndarray):
    """``rgb`` converted to a :data:`PIX_FMT` frame whose row padding is zero.

    A plane's rows are padded to an aligned stride, and FFmpeg leaves that padding uninitialised. x264's SIMD code
    reads it, so a frame whose width is not a multiple of the alignment encoded to different bytes about once in 300
    runs (seen in CI). Converting here and zeroing the padding makes the encoder's input, and so its output, the same
    every time."""
    import av

    frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(rgb), format="rgb24").reformat(format=PIX_FMT)
    for plane in frame.planes:
        np.frombuffer(memoryview(plane), dtype=np.uint8).reshape(-1, plane.line_size)[:, plane.width:] = 0
    return frame


def decode(path: Path | str) -> np.ndarray:
    """Every frame of the video at ``path`` as [T, H, W, 3] uint8 RGB."""
    import av

    try:
        with av.open(str(path)) as container:
            return np.stack([f.to_ndarray(format="rgb24") for f in container.decode(video=0)])
    except (av.error.FFmpegError, ValueError) as exc:
        raise VideoError(f"{path}: cannot decode the video ({exc})") from exc


__all__ = ["CODECS", "DEFAULT_CODEC", "VideoError", "decode", "encode"]
