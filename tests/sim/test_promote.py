"""Immutable versions: `gendex train` writes a run folder and leaves the version alone; `gendex promote` publishes the
version plus the run's policy as the next version, which registers and runs the policy."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
from typer.testing import CliRunner

from gendex.cli import app
from gendex.solve.executor import StageExecutor
from gendex.train.presets import PRESETS
from gendex.train.train import train_stage
from gendex_envs.registry import register_tasks, resolve_task, unregister_tasks
from gendex_envs.task_version import Artifacts, TaskLayout

TINY = dataclasses.replace(PRESETS["cpu"], n_steps=128, batch_size=64, n_epochs=1)


def test_train_then_promote_makes_a_new_version_and_keeps_the_old_one(task_copy, stage_run, tmp_path):
    v0 = task_copy("PickUpBottle", as_name="ScratchBottle")
    before = v0.file_digest()
    run = stage_run(v0, "lift_bottle", tmp_path / "run")
    r = train_stage(v0, "lift_bottle", steps=128, n_envs=1, run_dir=run, eval_episodes=1, progress=False,
                    preset=TINY, command="test")
    assert v0.file_digest() == before and v0.policy("lift_bottle") is None  # training left v0 untouched
    assert Artifacts(run).policy("lift_bottle") == r.policy

    result = CliRunner().invoke(app, ["promote", str(run)])
    assert result.exit_code == 0, result.output
    assert "published GenDex/ScratchBottle-v1 (lift_bottle policies)" in result.output
    assert v0.file_digest() == before
    new = [env_id for env_id in register_tasks([v0.tasks_root]) if env_id.endswith("-v1")]
    try:
        assert new == ["GenDex/ScratchBottle-v1"]
        v1 = resolve_task("ScratchBottle")  # the unversioned name now means v1
        assert v1.version == 1 and v1.policy("lift_bottle").model.read_bytes() == r.policy.model.read_bytes()
        assert v1.start_states("lift_bottle") is not None
        assert v1.provenance()["promotion"]["runs"] == [str(run)]
        listing = CliRunner().invoke(app, ["list", "ScratchBottle"])
        assert "GenDex/ScratchBottle-v1" in listing.output and "promoted from GenDex/ScratchBottle-v0" in listing.output

        # v1's executor runs the promoted policy; v0's runs the scripted lift
        for version, expected in ((v1, "lift_bottle.zip"), (v0, "scripted")):
            env = gym.make(version.env_id)
            ex = StageExecutor()
            try:
                obs, _ = env.reset(seed=0)
                ex.reset(env, obs)
                try:
                    while (a := ex.act(env, obs)) is not None:
                        obs, *_ = env.step(a)
                except Exception as exc:  # a policy trained for one rollout may miss the stage's goal
                    assert "did not reach the stage's goal" in str(exc)
                used = {log.stage: log.policy for log in ex.logs}
                assert used["lift_bottle"].endswith(expected), used
            finally:
                env.close()
    finally:
        unregister_tasks(new)


def test_a_run_of_another_version_or_a_changed_version_is_refused(task_copy, stage_run, tmp_path):
    v0 = task_copy("PickUpBottle", as_name="ScratchBottle")
    run = stage_run(v0, "lift_bottle", tmp_path / "run")
    train_stage(v0, "lift_bottle", steps=128, n_envs=1, run_dir=run, eval_episodes=1, progress=False, preset=TINY)
    other = CliRunner().invoke(app, ["train", "GenDex/PickUpBottle-v0", "--stage", "lift_bottle", "--out", str(run),
                                     "--steps", "2048"])
    assert other.exit_code == 2 and "is a training run of GenDex/ScratchBottle-v0" in other.output
    v0.files.reward.write_text(v0.files.reward.read_text() + "\n")  # someone edited the published version
    result = CliRunner().invoke(app, ["promote", str(run)])
    assert result.exit_code == 2 and "changed since the run was trained" in result.output
    not_a_run = CliRunner().invoke(app, ["promote", str(tmp_path)])
    assert not_a_run.exit_code == 2 and "is not a training run folder" in not_a_run.output
    assert not TaskLayout(v0.tasks_root / "ScratchBottle" / "v1").spec.exists()
