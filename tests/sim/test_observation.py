"""The observation contract of GenDex datasets (gendex_envs.observation): what is recorded is what the env gives a
policy through LeRobotObservation."""

import json

import gymnasium as gym
import numpy as np
import pyarrow.parquet as pq
import pytest

import gendex_envs  # noqa: F401
from gendex_envs.errors import GenDexError
from gendex_envs.observation import (
    ENVIRONMENT_STATE,
    STATE,
    LeRobotObservation,
    environment_state,
    environment_state_names,
)


def test_environment_state_names_every_object_pose_joint_and_goal():
    env = gym.make("GenDex/PushBlockToGoal-v0")
    try:
        env.reset(seed=4)
        u = env.unwrapped
        names, values = environment_state_names(env), environment_state(env)[0].numpy()
        assert len(names) == len(values) == 10 and names[:3] == ["block.pos.x", "block.pos.y", "block.pos.z"]
        np.testing.assert_allclose(values[:7], u.obj_pose("block").raw_pose[0].numpy(), atol=1e-6)
        np.testing.assert_allclose(values[7:], u.goal_pos[0].numpy(), atol=1e-6)
    finally:
        env.close()
    env = gym.make("GenDex/CloseMicrowave-v0")
    try:
        env.reset(seed=4)
        names, values = environment_state_names(env), environment_state(env)[0].numpy()
        assert names[-1] == "microwave.door_hinge.qpos"
        assert values[-1] == pytest.approx(env.unwrapped.joint_qpos("microwave")[0].item())
    finally:
        env.close()


def test_the_wrapper_gives_the_dataset_features_and_follows_the_scene():
    env = LeRobotObservation(gym.make("GenDex/PutAppleBowl-v1"))
    try:
        obs, _ = env.reset(seed=7)
        assert set(obs) == {STATE, ENVIRONMENT_STATE} and env.observation_space.contains(obs)
        first = obs[ENVIRONMENT_STATE].copy()
        obs, _ = env.reset(seed=8)  # another seed, another layout: the observation says so
        assert np.abs(obs[ENVIRONMENT_STATE] - first)[:2].max() > 1e-3
    finally:
        env.close()
    env = LeRobotObservation(gym.make("GenDex/PutAppleBowl-v1", obs_mode="rgb"))
    try:
        obs, _ = env.reset(seed=7)
        cams = [k for k in obs if k.startswith("observation.images.")]
        assert cams and all(obs[k].dtype == np.uint8 and obs[k].shape == (128, 128, 3) for k in cams)
        np.testing.assert_allclose(obs[ENVIRONMENT_STATE], first, atol=1e-6)  # same seed, same world
    finally:
        env.close()
    with pytest.raises(GenDexError, match="numpy API"):
        LeRobotObservation(gym.make("GenDex/PutAppleBowl-v1", gym_api=False))


def test_a_recorded_episode_exports_the_environment_state_the_env_gave(tmp_path):
    """A recorded episode keeps the world observation of every step, and the LeRobot export declares it by name:
    frame 0 is what LeRobotObservation returns at reset with the episode's seed."""
    from gendex.data.lerobot_v3 import LeRobotV3Writer
    from gendex.data.rollout import record_rollout

    env = LeRobotObservation(gym.make("GenDex/PutAppleBowl-v1", control_mode="pd_joint_delta_pos"))
    try:
        obs, _ = env.reset(seed=3)
        ep = record_rollout(env.env, 3, np.zeros((2, env.action_space.shape[0]), np.float32))
    finally:
        env.close()
    assert ep.environment_state.shape == (3, len(ep.environment_state_names))
    with LeRobotV3Writer(tmp_path / "ds", fps=ep.fps, robot_type="ur10e_shadowhand",
                         state_names=[f"s{i}" for i in range(ep.state.shape[1])],
                         action_names=[f"a{i}" for i in range(ep.action.shape[1])],
                         environment_state_names=list(ep.environment_state_names)) as w:
        w.add_episode(ep)
    info = json.loads((tmp_path / "ds" / "meta" / "info.json").read_text())
    assert info["features"][ENVIRONMENT_STATE]["names"] == list(ep.environment_state_names)
    frames = pq.read_table(next((tmp_path / "ds" / "data").rglob("*.parquet"))).to_pydict()
    np.testing.assert_allclose(frames[ENVIRONMENT_STATE][0], obs[ENVIRONMENT_STATE], atol=1e-6)
    np.testing.assert_allclose(frames[STATE][0], obs[STATE], atol=1e-6)
