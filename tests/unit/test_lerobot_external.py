"""GenDex datasets in lerobot itself: loaded by LeRobotDataset, a video frame decoded, ACT's config asked.

lerobot cannot live in the project venv (see scripts/lerobot_venv.sh), so a side venv is built (once, about 5.5 GB
from the machine's local torch files and the package index) and scripts/lerobot_check.py runs there on three kinds of
dataset this test writes: state only, state + environment state, state + environment state + AV1 video. Slow:
scripts/test.sh --slow."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

from gendex.data.episode import Episode
from gendex.data.lerobot_v3 import LeRobotV3Writer

ROOT = Path(__file__).resolve().parents[2]


def _episode(seed: int, t: int = 6) -> Episode:
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:32, 0:32]
    frames = np.stack([np.stack([(xx * 6 + 9 * k) % 256, (yy * 7) % 256, np.full_like(xx, 90)], -1)
                       for k in range(t + 1)]).astype(np.uint8)
    return Episode(task_id="GenDex/PutAppleBowl-v1", instruction="Put the apple into the bowl.", seed=seed,
                   control_mode="pd_joint_pos", control_joint="both", fps=20,
                   state=rng.normal(size=(t + 1, 6)).astype(np.float32), action=rng.normal(size=(t, 3)).astype(
                       np.float32), reward=np.zeros(t, np.float32), success=np.zeros(t, bool),
                   fail=np.zeros(t, bool), env_states=np.zeros((t + 1, 2), np.float32),
                   environment_state=rng.normal(size=(t + 1, 7)).astype(np.float32),
                   environment_state_names=tuple(f"apple.{f}" for f in ("pos.x", "pos.y", "pos.z", "quat.w",
                                                                          "quat.x", "quat.y", "quat.z")),
                   images={"left_overhead": frames})


def _write(root: Path, world: bool, video: bool, conventions: int = 1, per_episode: bool = False) -> Path:
    """``per_episode``: action 1 constant within each episode, 0 in the first and 1.4 in the second (which fingers
    a grasp curls)."""
    with LeRobotV3Writer(root, fps=20, robot_type="ur10e_shadowhand", state_names=[f"q{i}" for i in range(6)],
                         action_names=["a0", "a1", "a2"],
                         environment_state_names=list(_episode(0).environment_state_names) if world else None,
                         cameras={"left_overhead": (32, 32)} if video else None,
                         video_codec="libsvtav1" if video else None, conventions=conventions) as w:
        for seed in range(2):
            ep = _episode(seed)
            if per_episode:
                ep.action[:, 1] = 1.4 * seed
            w.add_episode(ep)
    return root


@pytest.mark.slow
def test_lerobot_loads_every_kind_of_gendex_dataset_and_act_accepts_world_or_video(tmp_path):
    python = subprocess.run(["bash", str(ROOT / "scripts" / "lerobot_venv.sh")], capture_output=True, text=True,
                            check=True).stdout.strip().splitlines()[-1]
    roots = [_write(tmp_path / "state", False, False), _write(tmp_path / "world", True, False),
             _write(tmp_path / "video", True, True), _write(tmp_path / "quantiles", True, True, conventions=2),
             _write(tmp_path / "mean", True, False, conventions=2, per_episode=True),
             _write(tmp_path / "pooled", True, False, conventions=3, per_episode=True)]
    run = subprocess.run([python, str(ROOT / "scripts" / "lerobot_check.py"), *map(str, roots)], capture_output=True,
                         text=True, timeout=600)
    reports = {Path(r["root"]).name: r for r in map(json.loads, run.stdout.splitlines())}
    assert run.returncode == 0, (run.stdout, run.stderr[-2000:])
    for name in ("state", "world", "video"):
        assert reports[name]["frames"] == 12 and reports[name]["episodes"] == 2
        assert reports[name]["task"] == "Put the apple into the bowl."
    assert reports["state"]["act"].startswith("refused") and "environment state" in reports["state"]["act"]
    assert reports["world"]["act"] == "accepted" and reports["video"]["act"] == "accepted"
    assert reports["video"]["decoded"] == {"observation.images.left_overhead": [3, 32, 32]}
    # pi0.5 normalises state and action by the 1st and 99th percentiles: conventions 2's stats have them, 1's do not
    assert reports["quantiles"]["pi05_norm"].startswith("accepted"), reports["quantiles"]
    assert reports["video"]["pi05_norm"].startswith("refused") and "q01" in reports["video"]["pi05_norm"]
    assert reports["quantiles"]["frames"] == 12 and reports["quantiles"]["act"] == "accepted"
    # lerobot's mean of the episodes' quantiles collapses a value constant within episodes: the check sees 1e8;
    # the dataset's own quantiles (conventions 3) keep the frame (episode 1's first) at 1
    assert reports["mean"]["pi05_norm"].startswith("degenerate"), reports["mean"]
    assert reports["pooled"]["pi05_norm"].startswith("accepted"), reports["pooled"]
