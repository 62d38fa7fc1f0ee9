"""Gymnasium's own conventions: the time limit in the registered spec, the default action space drives arm and hand
(the space `gendex collect` records in), batched truncation per sub-scene, a clear error for a viewer without a
display."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pyarrow.parquet as pq
import pytest
import torch

from gendex.data.collector import CollectConfig, collect
from gendex.solve import SOLVER_ENV_KWARGS, SOLVERS
from gendex_envs.agents.ur10e_shadow import ALL_JOINTS, COUPLED_DISTAL
from gendex_envs.errors import RenderModeError
from gendex_envs.registry import REFERENCE_TASKS, registered_tasks

TASK = "GenDex/PutAppleBowl-v0"


def test_the_registered_spec_carries_each_tasks_time_limit():
    """The reference tasks' versions here; every version's is `gendex check`'s ``time_limit`` check (the default
    suite runs it on a sample and the changed versions, tests/sim/test_check.py; the slow suite on all)."""
    for env_id, version in registered_tasks().items():
        if version.name in REFERENCE_TASKS:
            assert gym.spec(env_id).max_episode_steps == version.spec.max_episode_steps, env_id


def test_max_episode_steps_passed_to_make_changes_the_limit(make_env):
    env = make_env(TASK, max_episode_steps=3)
    assert env.spec.max_episode_steps == 3
    env.reset(seed=0)
    hold = env.unwrapped.agent.controller.free_targets()[0].numpy()
    flags = [env.step(hold)[3] for _ in range(3)]
    assert flags == [False, False, True] and all(isinstance(f, bool) for f in flags)


def test_the_default_env_drives_arm_and_hand_with_absolute_targets(make_env):
    env = make_env(TASK)
    u = env.unwrapped
    assert (u.control_mode, u.control_joint) == ("pd_joint_pos", "both")
    assert env.action_space.shape == (len(ALL_JOINTS) - len(COUPLED_DISTAL),)  # 6 arm + 20 hand, distals follow
    assert (u.control_mode, u.control_joint) == (SOLVER_ENV_KWARGS["stages"]["control_mode"],
                                                SOLVER_ENV_KWARGS["stages"]["control_joint"])


def test_a_collected_datasets_actions_step_the_default_env(tmp_path):
    """The LeRobot rows of a `gendex collect` episode are actions of plain gym.make(id): replayed there, they reach
    the same end state and success."""
    out = tmp_path / "ds"
    cfg = CollectConfig(task_id=TASK, num_success=1, out=out, formats=("lerobot",), seed=5, max_attempts=3,
                        **SOLVER_ENV_KWARGS["stages"])
    state = collect(cfg, SOLVERS["stages"])
    assert state.successes == 1
    table = pq.read_table(next((out / "lerobot" / "data").rglob("*.parquet"))).to_pydict()
    actions = np.asarray(table["action"], dtype=np.float32)
    env = gym.make(TASK)
    try:
        assert actions.shape[1:] == env.action_space.shape
        env.reset(seed=state.kept_seeds[0])
        for a in actions:
            assert env.action_space.contains(a)
            _, _, terminated, truncated, info = env.step(a)
        assert bool(info["success"]) and bool(table["next.success"][-1])
    finally:
        env.close()


def test_a_stage_env_truncates_at_the_stages_horizon(make_env):
    env = make_env(TASK, stage="reach_apple", control_mode="pd_joint_delta_pos")
    horizon = env.unwrapped.stage_spec.horizon
    env.reset(seed=0)
    zero = np.zeros(env.action_space.shape, dtype=np.float32)
    truncated = [env.step(zero)[3] for _ in range(horizon)]
    assert truncated[-1] and not any(truncated[:-1])


def test_the_batched_api_truncates_each_sub_scene_with_a_tensor(make_env):
    env = make_env(TASK, gym_api=False, max_episode_steps=2)
    env.reset(seed=0)
    hold = env.unwrapped.agent.controller.free_targets()
    flags = [env.step(hold)[3] for _ in range(2)]
    assert all(isinstance(f, torch.Tensor) and f.dtype == torch.bool and f.shape == (1,) for f in flags)
    assert [bool(f[0]) for f in flags] == [False, True]


def test_human_rendering_without_a_display_is_a_clear_error(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(RenderModeError, match=r"render_mode='human' opens a viewer window.*no display.*'rgb_array'"):
        gym.make(TASK, render_mode="human")
    with pytest.raises(RenderModeError, match=r"render_mode='video' is not a mode; allowed: \[None, 'rgb_array'"):
        gym.make(TASK, render_mode="video")


def test_unwrapped_is_the_torch_batched_task_env(make_env):
    env = make_env(TASK)
    obs, _ = env.reset(seed=0)
    assert isinstance(obs, np.ndarray) and obs.ndim == 1  # the numpy API: no batch dimension
    pose = env.unwrapped.obj_pose("apple").p
    assert isinstance(pose, torch.Tensor) and pose.shape == (1, 3)  # ManiSkill's batched tensors underneath
