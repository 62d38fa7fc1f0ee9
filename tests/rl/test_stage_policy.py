"""Stage envs and trained policies: a policy sees the same observation and drives the same joint targets whether it
runs in its own stage env or inside the stage executor's env, and the executor runs it when the task has one."""

import dataclasses

import numpy as np
import pytest
import torch

from gendex.solve.executor import StageExecutor
from gendex.solve.policy import StagePolicy, stage_observation
from gendex.train.envs import make_stage_env
from gendex.train.start_states import collect_executor_states
from gendex_envs.errors import StageError
from gendex_envs.registry import make_env
from gendex_envs.start_states import StartStates
from gendex_envs.task_version import Artifacts


@pytest.fixture
def bottle(task_version):
    return task_version("PickUpBottle", 0)


class _FixedModel:
    """Stands in for an SB3 model: always the same normalized action."""

    def __init__(self, action):
        self.action = np.asarray(action, dtype=np.float32)

    def predict(self, obs, deterministic=True):
        return np.broadcast_to(self.action, (len(obs), len(self.action))).copy(), None


def _policy(version, stage, control_joint, action, dim):
    return StagePolicy(stage=stage, control_joint=control_joint, judge=version.judge(stage), model=_FixedModel(action),
                       obs_mean=np.zeros(dim, np.float32), obs_var=np.ones(dim, np.float32), clip_obs=1e9, meta={})


def test_policy_sees_and_drives_the_same_in_the_executor_env(bottle):
    stage_env = make_stage_env(bottle, "approach_bottle", training=False)
    full = make_env(bottle, control_mode="pd_joint_pos", control_joint="both", gym_api=False)
    try:
        obs, _ = stage_env.reset(seed=3)
        full.reset(seed=3)
        policy = _policy(bottle, "approach_bottle", "arm", np.linspace(-1, 1, 6), obs.shape[-1])
        np.testing.assert_allclose(stage_observation(full, policy.judge)[0].cpu().numpy(), obs, atol=1e-5)
        for _ in range(5):  # same action in both envs: delta controller there, absolute targets here
            action = policy.predict(obs[None])[0]
            obs, *_ = stage_env.step(action)
            free = full.unwrapped.agent.controller.free_idx.cpu().numpy()
            target = policy.targets(full, action[None])[0].cpu().numpy()
            full.step(target[free])
        np.testing.assert_allclose(stage_observation(full, policy.judge)[0].cpu().numpy(), obs, atol=1e-4)
        moved = full.unwrapped.agent.robot.get_qpos()[0, :6] - torch.tensor(
            [2.683, -1.71, 2.408, -0.699, 1.112, 0.0])
        assert moved.abs().max() > 0.05  # the arm really moved (the comparison is not between two idle robots)
    finally:
        stage_env.close()
        full.close()


def test_later_stage_needs_start_states_and_restores_them(bottle, tmp_path):
    with pytest.raises(StageError, match="has no start states for it"):
        make_stage_env(bottle, "grasp_bottle", training=False)
    got = collect_executor_states(bottle, "grasp_bottle", 2, seed=0)
    assert len(got.states) == 2 and got.env_steps > 0
    path = got.states.save(tmp_path / "grasp_bottle.npz")
    env = make_stage_env(bottle, "grasp_bottle", start_states=StartStates.load(path), training=False)
    try:
        u = env.unwrapped
        env.reset(seed=0)
        assert u.control_joint == "hand" and env.action_space.shape == (20,)  # 2 wrist + 18 fingers (distals follow)
        row = [i for i in range(2) if np.allclose(u.get_state()[0].cpu().numpy(), got.states.state[i], atol=1e-5)]
        assert row, "the reset state is none of the saved start states"
        # obj_height measures from where the bottle stood when the task episode began, not from the restored pose
        np.testing.assert_allclose(u.init_obj_pos("bottle")[0].cpu().numpy(),
                                   got.states.obj_reset_pos["bottle"][row[0]])
        assert abs(float(u.obj_height("bottle")[0])) < 0.02
        assert env.unwrapped.stage_spec.horizon == 40
    finally:
        env.close()


def test_executor_runs_a_present_policy(bottle, stage_run, tmp_path):
    """With a trained policy of a stage in its sources the executor runs it (here: a real SB3 model trained for one
    rollout, in a training run folder)."""
    from gendex.train.presets import PRESETS
    from gendex.train.train import train_stage

    run = stage_run(bottle, "lift_bottle", tmp_path / "run")
    r = train_stage(bottle, "lift_bottle", steps=256, n_envs=1, run_dir=run, eval_episodes=1, progress=False,
                    preset=dataclasses.replace(PRESETS["cpu"], n_steps=256, batch_size=64, n_epochs=1))
    layout = Artifacts(run).layout
    assert r.policy.model == layout.policy("lift_bottle") and r.policy.model.is_file()
    assert layout.start_states("lift_bottle").is_file() and layout.record("run").is_file()
    assert (layout.policy_curves("lift_bottle") / "progress.csv").is_file()
    assert bottle.policy("lift_bottle") is None  # the version itself is untouched
    env = make_env(bottle, control_mode="pd_joint_pos", control_joint="both")
    ex = StageExecutor(policy_sources=[Artifacts(run)])
    try:
        obs, _ = env.reset(seed=0)
        ex.reset(env, obs)
        steps = 0
        try:
            while (a := ex.act(env, obs)) is not None and steps < 400:
                obs, *_ = env.step(a)
                steps += 1
        except Exception as e:  # an untrained lift policy may well not reach the goal: that is allowed here
            assert "did not reach the stage's goal" in str(e)
        used = {log.stage: log.policy for log in ex.logs}
        assert used["grasp_bottle"] == "scripted" and used["lift_bottle"].endswith("lift_bottle.zip")
        assert next(log for log in ex.logs if log.stage == "lift_bottle").steps > 0
    finally:
        env.close()


def test_a_whole_task_policy_is_judged_by_the_tasks_success(bottle, tmp_path):
    """The ablation's 'no sub-goals' policy trains on the whole task: it loads with the task's judge."""
    from gendex.solve.policy import WHOLE_TASK
    from gendex.train.presets import PRESETS
    from gendex.train.train import train_stage

    r = train_stage(bottle, None, steps=128, n_envs=1, run_dir=tmp_path / "run", control_joint="both",
                    eval_episodes=1, progress=False,
                    preset=dataclasses.replace(PRESETS["cpu"], n_steps=128, batch_size=64, n_epochs=1))
    assert r.stage == WHOLE_TASK and r.policy.meta()["stage"] == WHOLE_TASK
    policy = StagePolicy.load(bottle, r.policy)
    assert policy.judge.stage is None and policy.judge.conditions == bottle.spec.success.conditions


def test_warm_start_loads_a_policy_and_resets_its_noise(task_version):
    """``gendex train --init-from``: the fresh PPO acts as the policy it starts from, with the preset's noise."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    from gendex.train.presets import PRESETS, TrainingError
    from gendex.train.train import policy_to_start_from, warm_start

    v0 = task_version("RotateTennisBall", 0)
    files = policy_to_start_from(v0, "rotate_ball", "GenDex/RotateTennisBall-v0")
    assert files.model == v0.policy("rotate_ball").model
    with pytest.raises(TrainingError, match="another task"):
        policy_to_start_from(v0, "rotate_ball", "GenDex/PickUpBottle-v0")
    venv = VecNormalize(DummyVecEnv([lambda: make_stage_env(v0, "rotate_ball")]), clip_obs=10.0)
    try:
        model = PPO("MlpPolicy", venv, device="cpu", **PRESETS["cpu"].ppo_kwargs())
        record = warm_start(model, venv, files, "hand", -1.2)
        assert record["steps"] == files.meta()["steps"] and record["model"].endswith("v0/policies/rotate_ball.zip")
        assert torch.allclose(model.policy.log_std, torch.full_like(model.policy.log_std, -1.2))
        source = StagePolicy.load(v0, files)
        obs = venv.reset()
        raw = venv.get_original_obs()
        for _ in range(3):  # same actions as the source policy on the states the stage env visits
            action, _ = model.predict(obs, deterministic=True)
            np.testing.assert_allclose(np.clip(action, -1, 1), source.predict(raw), atol=1e-4)
            obs, *_ = venv.step(action)
            raw = venv.get_original_obs()
        with pytest.raises(TrainingError, match="cannot start from it"):
            warm_start(model, venv, files, "arm", -1.2)
    finally:
        venv.close()
