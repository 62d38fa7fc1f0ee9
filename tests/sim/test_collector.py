"""Collector: keeps successful episodes only, resumes after interruption, formats agree, replay reproduces."""

import dataclasses
import json
import shutil

import pyarrow.parquet as pq
import pytest
import yaml
from typer.testing import CliRunner

import gendex.data.collector as collector
from gendex.cli import app
from gendex.data.collector import CollectConfig, collect
from gendex.solve import HoldSolver
from gendex_envs.registry import register_tasks, resolve_task, unregister_tasks
from gendex_envs.task_version import TaskLayout

TASK = "GenDex/ScratchNear-v0"


@pytest.fixture(scope="module")
def near_task(tmp_path_factory):
    """PutAppleBowl with success 'apple within 28 cm of the bowl': true for some reset seeds, false for others."""
    root = tmp_path_factory.mktemp("tasks")
    folder = root / "ScratchNear" / "v0"
    shutil.copytree(resolve_task("GenDex/PutAppleBowl-v0").root, folder)
    spec = TaskLayout(folder).spec
    raw = yaml.safe_load(spec.read_text())
    raw["name"] = "ScratchNear"
    raw["success"] = {"description": "apple near the bowl",
                      "conditions": [{"type": "near", "object": "apple", "target": "bowl", "max_dist_m": 0.28}]}
    spec.write_text(yaml.safe_dump(raw))
    register_tasks([root])
    yield TASK
    unregister_tasks([TASK])


def _cfg(out, **kw):
    return CollectConfig(task_id=TASK, num_success=3, out=out, formats=("lerobot", "h5"), seed=0,
                         control_mode="pd_joint_delta_pos", **kw)


def _counts(out):
    info = json.loads((out / "lerobot" / "meta" / "info.json").read_text())
    rows = sum(pq.read_table(f).num_rows for f in (out / "lerobot" / "data").rglob("file-*.parquet"))
    h5 = json.loads((out / "trajectories.json").read_text())
    return info["total_episodes"], info["total_frames"], rows, len(h5["episodes"])


def test_keeps_only_successes_and_formats_agree(near_task, tmp_path):
    state = collect(_cfg(tmp_path / "a"), lambda: HoldSolver(steps=4))
    assert state.successes == 3 and state.attempts > 3, "some seeds must fail the 'near' condition"
    episodes, frames, rows, h5_episodes = _counts(tmp_path / "a")
    # success terminates an episode: kept ones end at their first step, failed attempts run the solver's 4 steps
    assert episodes == h5_episodes == 3 and frames == rows == 3
    h5 = json.loads((tmp_path / "a" / "trajectories.json").read_text())
    assert [e["episode_seed"] for e in h5["episodes"]] == state.kept_seeds
    assert all(e["success"] for e in h5["episodes"])
    assert state.env_steps == 4 * (state.attempts - 3) + 3


def test_resume_after_kill_between_export_and_commit(near_task, tmp_path, monkeypatch):
    """Killed after the exporters took an episode but before the state commit: resuming does not duplicate it."""
    out = tmp_path / "b"
    real_write = collector.write_json
    calls = {"n": 0}

    def dying_write(path, data, **kwargs):
        if data["kept_seeds"] and len(data["kept_seeds"]) == 2 and calls["n"] == 0:
            calls["n"] += 1
            raise KeyboardInterrupt("killed")
        real_write(path, data, **kwargs)

    monkeypatch.setattr(collector, "write_json", dying_write)
    with pytest.raises(KeyboardInterrupt):
        collect(_cfg(out), lambda: HoldSolver(steps=4))
    assert _counts(out)[0] == 2  # the second success reached the exporters, the state says one
    state = collect(_cfg(out), lambda: HoldSolver(steps=4))
    episodes, frames, rows, h5_episodes = _counts(out)
    assert state.successes == episodes == h5_episodes == 3 and frames == rows == 3
    reference = collect(_cfg(tmp_path / "ref"), lambda: HoldSolver(steps=4))
    assert state.kept_seeds == reference.kept_seeds and state.attempts == reference.attempts


def test_cli_collect_then_replay(near_task, tmp_path):
    out = tmp_path / "c"
    result = CliRunner().invoke(app, ["collect", TASK, "--num-success", "2", "--out", str(out), "--format", "both"])
    assert result.exit_code == 0, result.output
    assert "2/" in result.output and (out / "lerobot" / "README.md").is_file()
    card = (out / "lerobot" / "README.md").read_text()  # the exact env the actions belong to
    assert (f"gym.make('{TASK}', control_mode='pd_joint_pos', control_joint='both', obs_mode='state', "
            "reconfiguration_freq=1)") in card
    replayed = CliRunner().invoke(app, ["replay", str(out / "trajectories.h5")])
    assert replayed.exit_code == 0, replayed.output
    assert replayed.output.count(": OK") == 2


def test_two_workers_give_the_same_dataset(near_task, tmp_path):
    one = collect(_cfg(tmp_path / "w1"), HoldSolver)
    two = collect(_cfg(tmp_path / "w2"), HoldSolver, workers=2)
    assert two.kept_seeds == one.kept_seeds and two.attempts == one.attempts and two.env_steps == one.env_steps
    assert _counts(tmp_path / "w2") == _counts(tmp_path / "w1")


def test_cameras_are_recorded_as_video_at_the_asked_resolution(near_task, tmp_path):
    """--cameras with the default video codec: the dataset's info names a video_path, each kept episode has an MP4
    per camera holding one frame per action at the asked resolution, and the card's gym.make call says so."""
    from gendex_envs.video import decode

    cfg = _cfg(tmp_path, cameras=("left_overhead",), resolution=64)
    state = collect(dataclasses.replace(cfg, num_success=1, formats=("lerobot",)), lambda: HoldSolver(steps=4))
    assert state.successes == 1
    root = tmp_path / "lerobot"
    info = json.loads((root / "meta" / "info.json").read_text())
    key = "observation.images.left_overhead"
    assert info["video_path"] and info["features"][key]["dtype"] == "video"
    assert info["features"][key]["shape"] == [64, 64, 3]
    [video] = (root / "videos" / key).rglob("*.mp4")
    assert decode(video).shape == (info["total_frames"], 64, 64, 3)
    assert cfg.env_kwargs()["sensor_resolution"] == 64 and cfg.env_kwargs()["obs_mode"] == "rgb"
    assert cfg.env_kwargs()["sensors"] == list(cfg.cameras)  # only the recorded cameras render
