"""Stage envs and trained policies: a policy sees the same observation and drives the same joint targets whether it
runs in its own stage env or inside the stage executor's env, and the executor runs it when the task has one."""

import dataclasses

import numpy as np
import pytest
import torch

import gendex_envs  # noqa: F401
from gendex_envs.errors import StageError
from gendex_envs.registry import make_task_env
from gendex_envs.reward_module import load_reward_module
from gendex_envs.solve.executor import StageExecutor
from gendex_envs.solve.policy import StagePolicy, stage_observation
from gendex_envs.stage import StartStates, stage_reward_path
from generator.rl.envs import make_stage_env
from generator.rl.start_states import collect_executor_states

BOTTLE = "generated_tasks/PickUpBottle/v0"


class _FixedModel:
    """Stands in for an SB3 model: always the same normalized action."""

    def __init__(self, action):
        self.action = np.asarray(action, dtype=np.float32)

    def predict(self, obs, deterministic=True):
        return np.broadcast_to(self.action, (len(obs), len(self.action))).copy(), None


def _policy(stage, control_joint, action, dim):
    module = load_reward_module(stage_reward_path(BOTTLE, stage))
    return StagePolicy(stage=stage, control_joint=control_joint, module=module, model=_FixedModel(action),
                       obs_mean=np.zeros(dim, np.float32), obs_var=np.ones(dim, np.float32), clip_obs=1e9, meta={})


def test_policy_sees_and_drives_the_same_in_the_executor_env():
    stage_env = make_stage_env(BOTTLE, "approach_bottle", training=False)
    full = make_task_env(BOTTLE, control_mode="pd_joint_pos", control_joint="both")
    try:
        obs, _ = stage_env.reset(seed=3)
        full.reset(seed=3)
        policy = _policy("approach_bottle", "arm", np.linspace(-1, 1, 6), obs.shape[-1])
        np.testing.assert_allclose(stage_observation(full, policy.module)[0].cpu().numpy(), obs, atol=1e-5)
        for _ in range(5):  # same action in both envs: delta controller there, absolute targets here
            action = policy.predict(obs[None])[0]
            obs, *_ = stage_env.step(action)
            free = full.unwrapped.agent.controller.free_idx.cpu().numpy()
            target = policy.targets(full, action[None])[0].cpu().numpy()
            full.step(target[free])
        np.testing.assert_allclose(stage_observation(full, policy.module)[0].cpu().numpy(), obs, atol=1e-4)
        moved = full.unwrapped.agent.robot.get_qpos()[0, :6] - torch.tensor(
            [2.683, -1.71, 2.408, -0.699, 1.112, 0.0])
        assert moved.abs().max() > 0.05  # the arm really moved (the comparison is not between two idle robots)
    finally:
        stage_env.close()
        full.close()


def test_later_stage_needs_start_states_and_restores_them(tmp_path):
    with pytest.raises(StageError, match="no start states"):
        make_stage_env(BOTTLE, "grasp_bottle", training=False)
    got = collect_executor_states(BOTTLE, "grasp_bottle", 2, seed=0)
    assert len(got.states) == 2 and got.env_steps > 0
    path = got.states.save(tmp_path / "grasp_bottle.npz")
    env = make_stage_env(BOTTLE, "grasp_bottle", start_states=StartStates.load(path), training=False)
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


def test_executor_runs_a_present_policy(tmp_path):
    """With policies/<stage>.zip present the executor runs it (here: a real SB3 model trained for one rollout)."""
    from generator.rl.train import train_stage

    r = train_stage(BOTTLE, "lift_bottle", steps=256, n_envs=1, policy_dir=tmp_path / "policies",
                    eval_episodes=1, progress=False,
                    preset=dataclasses.replace(__import__("generator.rl.presets", fromlist=["x"]).PRESETS["cpu"],
                                               n_steps=256, batch_size=64, n_epochs=1))
    assert r.policy_path.is_file() and (tmp_path / "start_states" / "lift_bottle.npz").is_file()
    assert (tmp_path / "policies" / "lift_bottle" / "progress.csv").is_file()
    env = make_task_env(BOTTLE, control_mode="pd_joint_pos", control_joint="both")
    ex = StageExecutor(policy_dir=tmp_path / "policies")
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
