"""Do the same frames always encode to the same bytes? Counts the encodes that stray, under CPU load.

Each round writes three small LeRobot v3.0 datasets as ``tests/unit/test_lerobot_v3.py``'s video test does (one
writer; one closed and reopened; one killed and resumed), so every one of three episodes is encoded three times a
round, among the writer's other work (parquet, muxing, journal). Every encode's output is hashed per input, and so
are the YUV planes handed to the encoder (padding included); an encode whose bytes differ from the most common bytes
for the same frames strayed, and ``input_differed`` counts the strays whose planes differed too (0: the encoder
itself strayed). ``--load K`` keeps K busy-loop processes
running meanwhile (the strays were seen only on a loaded machine). ``--unrestricted`` lets x264 use its AVX-512
kernels (what :func:`gendex_envs.video._encoder_options` stops on AVX-512 CPUs).

Usage (the record in ``benchmarks/results/video.md``)::

    .venv/bin/python benchmarks/video_determinism.py --rounds 400 --load 3 [--unrestricted] [--codec libsvtav1]
"""

from __future__ import annotations

import argparse
import collections
import hashlib
import json
import logging
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

# isort: off
import gendex_envs.blas  # noqa: F401 - first: it pins OpenBLAS's kernels before numpy loads
# isort: on

import numpy as np

import gendex.data.lerobot_v3 as lv3
import gendex_envs.video as video
from gendex.data.episode import Episode

FPS, H, W = 10, 16, 24


def _episode(t: int, seed: int) -> Episode:
    """A ``t``-step episode whose camera frames are smooth ramps (the test's ``_smooth_episode``)."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:H, 0:W]
    frames = np.stack([np.stack([(xx * 8 + 10 * k) % 256, (yy * 12) % 256, np.full_like(xx, 40 * seed % 256)], -1)
                       for k in range(t + 1)]).astype(np.uint8)
    return Episode(task_id="GenDex/Bench-v0", instruction="bench", seed=seed, control_mode="pd_joint_pos",
                   control_joint="all", fps=FPS, state=rng.standard_normal((t + 1, 3)).astype(np.float32),
                   action=rng.standard_normal((t, 2)).astype(np.float32), reward=np.zeros(t, np.float32),
                   success=np.zeros(t, bool), fail=np.zeros(t, bool), env_states=np.zeros((t + 1, 2), np.float32),
                   images={"front": frames})


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=100)
    ap.add_argument("--load", type=int, default=3, help="busy-loop processes running meanwhile")
    ap.add_argument("--codec", default="libx264", choices=sorted(video.CODECS))
    ap.add_argument("--unrestricted", action="store_true", help="let x264 use its AVX-512 kernels")
    args = ap.parse_args(argv)
    logging.getLogger("gendex").setLevel(logging.ERROR)  # each killed writer logs its resume
    if args.unrestricted:
        video._cpu_has_avx512 = lambda: False  # noqa: SLF001 - the choice under test
    outputs: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
    planes: list[bytes] = []
    encode, yuv_frame = lv3.encode, video._yuv_frame  # noqa: SLF001 - wrapped to hash the encoder's input

    def hashing_yuv_frame(rgb):
        frame = yuv_frame(rgb)
        planes.append(hashlib.sha256(b"".join(bytes(memoryview(p)) for p in frame.planes)).digest())
        return frame

    def counting_encode(frames, path, fps, codec):
        planes.clear()
        encode(frames, path, fps, codec)
        key = hashlib.sha256(np.ascontiguousarray(frames).tobytes()).hexdigest()
        outputs[key][(hashlib.sha256(Path(path).read_bytes()).hexdigest(), tuple(planes))] += 1

    video._yuv_frame, lv3.encode = hashing_yuv_frame, counting_encode  # noqa: SLF001
    eps = [_episode(6, 1), _episode(4, 2), _episode(5, 3)]

    def open_writer(root: Path) -> lv3.LeRobotV3Writer:
        return lv3.LeRobotV3Writer(root, fps=FPS, robot_type="bench", state_names=["a", "b", "c"],
                                   action_names=["x", "y"], cameras={"front": (H, W)}, video_codec=args.codec)

    busy = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(args.load)]
    try:
        for _ in range(args.rounds):
            tmp = Path(tempfile.mkdtemp())
            with open_writer(tmp / "a") as w:
                for e in eps:
                    w.add_episode(e)
            with open_writer(tmp / "b") as w:
                w.add_episode(eps[0])
            with open_writer(tmp / "b") as w:
                for e in eps[1:]:
                    w.add_episode(e)
            w = open_writer(tmp / "c")
            w.add_episode(eps[0])
            w.add_episode(eps[1])
            del w  # killed
            with open_writer(tmp / "c") as w:
                w.add_episode(eps[2])
            shutil.rmtree(tmp)
    finally:
        for p in busy:
            p.kill()
    encodes = sum(sum(c.values()) for c in outputs.values())
    strays = input_differed = 0
    for c in outputs.values():
        (_, common_planes), _ = c.most_common(1)[0]
        strays += sum(c.values()) - c.most_common(1)[0][1]
        input_differed += sum(n for (_, p), n in c.items() if p != common_planes)
    restricted = video._cpu_has_avx512() and args.codec == "libx264"  # noqa: SLF001
    print(json.dumps({"codec": args.codec, "restricted": restricted,
                      "load": args.load, "rounds": args.rounds, "encodes": encodes, "strays": strays,
                      "input_differed": input_differed}))


if __name__ == "__main__":
    main()
