"""`gendex train` / `gendex ablate` reject bad input with a named error (exit code 2), before any simulation."""

from typer.testing import CliRunner

from gendex.cli import app

runner = CliRunner()


def test_train_unknown_stage_names_the_stages():
    r = runner.invoke(app, ["train", "GenDex/PickUpBottle-v0", "--stage", "grasp_botle", "--steps", "2048"])
    assert r.exit_code == 2
    assert "no stage 'grasp_botle'" in r.output and "Did you mean: 'grasp_bottle'" in r.output


def test_train_unknown_preset_and_short_budget():
    r = runner.invoke(app, ["train", "GenDex/PickUpBottle-v0", "--stage", "0", "--preset", "fast"])
    assert r.exit_code == 2 and "unknown preset 'fast'" in r.output
    r = runner.invoke(app, ["train", "GenDex/PickUpBottle-v0", "--stage", "0", "--steps", "100"])
    assert r.exit_code == 2 and "less than one PPO rollout" in r.output


def test_train_unknown_task():
    r = runner.invoke(app, ["train", "GenDex/PickUpBotle-v0", "--stage", "0"])
    assert r.exit_code == 2 and "GenDex/PickUpBottle-v0" in r.output


def test_ablate_unknown_variant(tmp_path):
    r = runner.invoke(app, ["ablate", "--tasks", "PickUpBottle", "--variant", "rl_only", "--out", str(tmp_path)])
    assert r.exit_code == 2 and "unknown variants ['rl_only']" in r.output
