"""PPO learns: on a short stage (PickUpBottle's 60-step arm approach, 6 joints), a few thousand env steps of the
``cpu`` preset raise the mean evaluation return well above the untrained policy's, on the same evaluation seeds.
About a minute on two cores; not marked slow, so CI runs it with the default suite."""

import json

from generator.rl.train import progress_rows, train_stage

BOTTLE = "generated_tasks/PickUpBottle/v0"
STEPS = 16384


def test_ppo_raises_the_stage_return(tmp_path):
    r = train_stage(BOTTLE, "approach_bottle", steps=STEPS, seed=0, policy_dir=tmp_path / "policies",
                    eval_episodes=6, progress=False, checkpoint_every=8192)
    assert r.steps == STEPS
    # returns are sums of normalized rewards (each step in [0, 1]) over the 60-step horizon
    assert r.trained.mean_return > r.untrained.mean_return + 3.0, (r.trained, r.untrained)
    assert r.trained.successes > r.untrained.successes
    assert r.trained.mean_return > 1.5 * r.untrained.mean_return
    # what is saved with the policy: its record, its curve, its checkpoints
    meta = json.loads((tmp_path / "policies" / "approach_bottle.json").read_text())
    assert meta["control_joint"] == "arm" and meta["steps"] == STEPS and meta["preset"]["name"] == "cpu"
    assert meta["evaluation"]["trained"]["mean_return"] == r.trained.mean_return
    rows = progress_rows(tmp_path / "policies", "approach_bottle")
    assert [row["time/total_timesteps"] for row in rows][-1] == STEPS
    assert rows[-1]["rollout/ep_rew_mean"] > rows[0]["rollout/ep_rew_mean"]  # the training curve rises too
    assert sorted(p.name for p in (tmp_path / "policies" / "approach_bottle" / "checkpoints").iterdir()) == [
        "approach_bottle_16384_steps.zip", "approach_bottle_8192_steps.zip"]
