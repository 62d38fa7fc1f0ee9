"""PPO learns: on a short stage (PickUpBottle's 60-step arm approach, 6 joints), a few thousand env steps of the
``cpu`` preset raise the mean evaluation return well above the untrained policy's, on the same evaluation seeds.
About a minute alone: marked slow (`scripts/test.sh --slow`), as a measurement of learning; the default suite trains
and promotes a policy through the same code (tests/sim/test_promote.py) and runs one (tests/rl/test_stage_policy.py)."""

import pytest

from gendex.train.train import progress_rows, train_stage
from gendex_envs.task_version import Artifacts

STEPS = 16384


@pytest.mark.slow
def test_ppo_raises_the_stage_return(task_version, tmp_path):
    bottle = task_version("PickUpBottle", 0)
    before = bottle.file_digest()
    run = tmp_path / "run"
    r = train_stage(bottle, "approach_bottle", steps=STEPS, seed=0, run_dir=run, eval_episodes=6, progress=False,
                    checkpoint_every=8192)
    assert r.steps == STEPS
    # returns are sums of normalized rewards (each step in [0, 1]) over the 60-step horizon
    assert r.trained.mean_return > r.untrained.mean_return + 3.0, (r.trained, r.untrained)
    assert r.trained.successes > r.untrained.successes
    assert r.trained.mean_return > 1.5 * r.untrained.mean_return
    # what is saved with the policy: its record, its curve, its checkpoints
    meta = r.policy.meta()
    assert meta["control_joint"] == "arm" and meta["steps"] == STEPS and meta["preset"]["name"] == "cpu"
    assert meta["evaluation"]["trained"]["mean_return"] == r.trained.mean_return
    assert meta["source"] == "GenDex/PickUpBottle-v0"
    rows = progress_rows(run, "approach_bottle")
    assert [row["time/total_timesteps"] for row in rows][-1] == STEPS
    assert rows[-1]["rollout/ep_rew_mean"] > rows[0]["rollout/ep_rew_mean"]  # the training curve rises too
    checkpoints = Artifacts(run).layout.policy_checkpoints("approach_bottle")
    assert sorted(p.name for p in checkpoints.iterdir()) == [
        "approach_bottle_16384_steps.zip", "approach_bottle_8192_steps.zip"]
    assert bottle.file_digest() == before  # training never writes into the published version
