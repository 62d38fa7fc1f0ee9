"""Does appending an episode to a LeRobot v3.0 dataset cost the same at the 1 000th episode as at the first?

Writes ``--episodes`` synthetic episodes (``--frames`` frames each, ``--dim``-dim state and action, rewards; with
``--camera``, one ``--size`` px camera encoded as AV1 video) with :class:`~gendex.data.lerobot_v3.LeRobotV3Writer`
to a temporary folder, timing each ``add_episode`` (the episodes are built before the timed region), then
``close()``. Prints the mean time per episode of the first and the last ``--window`` episodes and their ratio (issue
44's goal: the last within 20 % of the first, i.e. ratio <= 1.2), the close time and the files written.

Run: ``.venv/bin/python benchmarks/dataset_writer.py [--episodes 1000] [--camera]``. ``--writer-from FILE`` times the
``LeRobotV3Writer`` of another copy of the module (e.g. ``git show <rev>:gendex/data/lerobot_v3.py > /tmp/old.py``)
for a comparison.
"""

from __future__ import annotations

import argparse
import importlib.util
import statistics
import tempfile
import time
from pathlib import Path

# isort: off
import gendex_envs.blas  # noqa: F401 - first: it pins OpenBLAS's kernels before numpy loads
# isort: on

import numpy as np

from gendex.data.episode import Episode


def episode(seed: int, frames: int, dim: int, size: int | None) -> Episode:
    rng = np.random.default_rng(seed)
    images = {}
    if size:
        yy, xx = np.mgrid[0:size, 0:size]
        images["front"] = np.stack([np.stack([(xx * 3 + 5 * k + seed) % 256, (yy * 4 + seed) % 256,
                                              np.full_like(xx, (40 * seed) % 256)], -1)
                                    for k in range(frames + 1)]).astype(np.uint8)
    return Episode(task_id="GenDex/PutAppleBowl-v1", instruction="Put the apple into the bowl.", seed=seed,
                   control_mode="pd_joint_pos", control_joint="both", fps=20,
                   state=rng.normal(size=(frames + 1, dim)).astype(np.float32),
                   action=rng.uniform(-1, 1, size=(frames, dim)).astype(np.float32),
                   reward=rng.uniform(size=frames).astype(np.float32), success=np.arange(frames) == frames - 1,
                   fail=np.zeros(frames, bool), env_states=np.zeros((frames + 1, 2), np.float32), images=images)


def writer_class(path: str | None):
    if path is None:
        from gendex.data.lerobot_v3 import LeRobotV3Writer

        return LeRobotV3Writer
    spec = importlib.util.spec_from_file_location("writer_under_test", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.LeRobotV3Writer


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=1000)
    parser.add_argument("--frames", type=int, default=120)
    parser.add_argument("--dim", type=int, default=30)
    parser.add_argument("--camera", action="store_true", help="one camera, stored as AV1 video")
    parser.add_argument("--size", type=int, default=64, help="camera image size in pixels")
    parser.add_argument("--window", type=int, default=100, help="episodes averaged at the start and at the end")
    parser.add_argument("--writer-from", default=None, help="time the LeRobotV3Writer of this module file instead")
    args = parser.parse_args()
    size = args.size if args.camera else None
    names = [f"q{i}" for i in range(args.dim)]
    cls = writer_class(args.writer_from)
    eps = [episode(s % 50, args.frames, args.dim, size) for s in range(min(args.episodes, 50))]  # reused cyclically
    times = []
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp) / "ds"
        w = cls(root, fps=20, robot_type="synthetic", state_names=names, action_names=names,
                cameras={"front": (size, size)} if size else None, video_codec="libsvtav1" if size else None)
        for k in range(args.episodes):
            t0 = time.perf_counter()
            w.add_episode(eps[k % len(eps)])
            times.append(time.perf_counter() - t0)
            if (k + 1) % 100 == 0:
                print(f"  {k + 1} episodes: last one {times[-1] * 1e3:.1f} ms", flush=True)
        t0 = time.perf_counter()
        w.close()
        closing = time.perf_counter() - t0
        files = sorted(p for p in root.rglob("*") if p.is_file())
        data = [p for p in files if p.suffix == ".parquet" and "data" in p.parts]
        videos = [p for p in files if p.suffix == ".mp4"]
        total = sum(p.stat().st_size for p in files)
    first = statistics.mean(times[:args.window])
    last = statistics.mean(times[-args.window:])
    print(f"{args.episodes} episodes x {args.frames} frames, {args.dim}-dim state/action"
          f"{f', one {size} px AV1 camera' if size else ''}: {len(data)} data files, {len(videos)} video files, "
          f"{total / 1e6:.1f} MB")
    print(f"time per episode: first {args.window} {first * 1e3:.2f} ms, last {args.window} {last * 1e3:.2f} ms, "
          f"ratio {last / first:.2f} (goal <= 1.2); close {closing:.2f} s; total {sum(times):.1f} s")


if __name__ == "__main__":
    main()
