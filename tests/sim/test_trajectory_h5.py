"""ManiSkill-style HDF5 + JSON trajectories of real GenDex rollouts, and their exact replay."""

import json

import gymnasium as gym
import h5py
import numpy as np
import pytest
import torch

from gendex.data.episode import Episode, EpisodeError
from gendex.data.rollout import (
    env_info,
    flat_env_state,
    object_positions,
    record_rollout,
    set_flat_env_state,
    state_layout,
)
from gendex.data.trajectory_h5 import (
    ReplayError,
    TrajectoryFileError,
    TrajectoryWriter,
    replay_episode,
    replay_file,
)

ENV_ID = "GenDex/PickUpBottle-v0"


def _actions(rng: np.random.Generator, steps: int, dim: int) -> np.ndarray:
    """Random actions whose arm part (shoulder pan -, lift +) sweeps the hand into the bottle by step ~7."""
    a = rng.uniform(-1, 1, (steps, dim)).astype(np.float32)
    a[:, :3] = np.clip(np.array([-1.0, 1.0, 0.0]) + 0.3 * rng.standard_normal((steps, 3)), -1, 1)
    return a


@pytest.fixture(scope="module")
def env():
    e = gym.make(ENV_ID, control_mode="pd_joint_delta_pos", control_joint="both")
    yield e
    e.close()


@pytest.fixture(scope="module")
def episodes(env):
    """Two recorded episodes: seed 3 (30 steps, the hand pushes the bottle) and seed 4 (12 steps)."""
    dim = env.action_space.shape[0]
    first = record_rollout(env, 3, _actions(np.random.default_rng(0), 30, dim), info={"source": "test"})
    second = record_rollout(env, 4, _actions(np.random.default_rng(1), 12, dim))
    return first, second


def _write(path, env, *eps) -> list[int]:
    with TrajectoryWriter(path, **env_info(env)) as w:
        return [w.add_episode(ep) for ep in eps]


def test_record_rollout_builds_a_full_episode(env, episodes):
    ep = episodes[0]
    u = env.unwrapped
    assert (ep.task_id, ep.seed, ep.control_mode, ep.control_joint, ep.fps) == (
        ENV_ID, 3, "pd_joint_delta_pos", "both", 20)
    n_dof = u.agent.robot.get_qpos().shape[1]
    assert ep.action.shape == (30, 26) and ep.state.shape == (31, 2 * n_dof)
    layout = state_layout(env)
    assert ep.env_states.shape == (31, max(s.stop for s in layout.values()))
    assert list(layout)[-1] == "controller/target_qpos"  # the frozen-joint targets are part of the env state
    start = object_positions(env, ep.env_states[0], layout)["bottle"]
    end = object_positions(env, ep.env_states[-1], layout)["bottle"]
    assert np.linalg.norm(end - start) > 0.02, "the rollout should push the bottle (a contact-rich replay)"


def test_file_layout_matches_maniskill(tmp_path, env, episodes):
    ep = episodes[0]
    assert _write(tmp_path / "demo", env, ep) == [0]
    with h5py.File(tmp_path / "demo.h5", "r") as f:
        assert list(f.keys()) == ["traj_0"]
        g = f["traj_0"]
        t, a, s, e = ep.length, ep.action.shape[1], ep.state.shape[1], ep.env_states.shape[1]
        expected = {"actions": ((t, a), np.float32), "terminated": ((t,), np.bool_), "truncated": ((t,), np.bool_),
                    "success": ((t,), np.bool_), "fail": ((t,), np.bool_), "rewards": ((t,), np.float32),
                    "env_states": ((t + 1, e), np.float32), "obs": ((t + 1, s), np.float32)}
        assert set(g.keys()) == set(expected)
        for key, (shape, dtype) in expected.items():
            assert g[key].shape == shape and g[key].dtype == dtype, key
            assert g[key].compression == "gzip", key
        np.testing.assert_array_equal(g["actions"][()], ep.action)
        np.testing.assert_array_equal(g["env_states"][()], ep.env_states)
        np.testing.assert_array_equal(g["terminated"][()], ep.success | ep.fail)
        assert not g["truncated"][()].any()  # 30 steps < max_episode_steps (200)
    meta = json.loads((tmp_path / "demo.json").read_text())
    assert meta["env_info"] == {"env_id": ENV_ID, "max_episode_steps": 200,
                                "env_kwargs": {"control_mode": "pd_joint_delta_pos", "control_joint": "both"}}
    (rec,) = meta["episodes"]
    assert rec["episode_id"] == 0 and rec["episode_seed"] == 3 and rec["reset_kwargs"] == {"seed": 3}
    assert rec["control_mode"] == "pd_joint_delta_pos" and rec["elapsed_steps"] == 30
    assert rec["success"] is False and rec["fail"] is False
    assert rec["info"]["control_joint"] == "both" and rec["info"]["success"] is False
    assert rec["info"]["source"] == "test" and rec["info"]["fps"] == 20


def test_replay_reproduces_the_episode(tmp_path, env, episodes):
    _write(tmp_path / "demo", env, episodes[0])
    r = replay_episode(tmp_path / "demo.h5", 0)
    assert r.episode_id == 0 and r.steps == 30
    assert r.success_recorded == r.success_replayed and r.success_steps_differing == 0
    assert set(r.object_pos_err_by_name) == {"bottle"}
    assert r.max_object_pos_err_m <= 1e-3, r
    assert r.max_env_state_err <= 1e-3, r  # deterministic physics: the whole state, robot included, replays
    assert r.reproduced()


def test_reopen_appends_and_drops_unlisted_groups(tmp_path, env, episodes):
    _write(tmp_path / "demo", env, episodes[0])
    with h5py.File(tmp_path / "demo.h5", "a") as f:  # a killed run: group written, JSON never updated
        f.create_group("traj_5").create_dataset("actions", data=np.zeros((3, 26), np.float32))
    with TrajectoryWriter(tmp_path / "demo.h5", **env_info(env)) as w:
        with h5py.File(tmp_path / "demo.h5", "r") as f:
            assert list(f.keys()) == ["traj_0"]
        assert w.add_episode(episodes[1]) == 1
        assert w.episode_ids == [0, 1]
    with h5py.File(tmp_path / "demo.h5", "r") as f:
        assert sorted(f.keys()) == ["traj_0", "traj_1"] and f["traj_1/actions"].shape == (12, 26)
    meta = json.loads((tmp_path / "demo.json").read_text())
    assert [(e["episode_id"], e["episode_seed"], e["elapsed_steps"]) for e in meta["episodes"]] == [(0, 3, 30),
                                                                                                   (1, 4, 12)]
    assert not list(tmp_path.glob(".*tmp"))  # the atomic JSON rewrite left no temp file
    results = replay_file(tmp_path / "demo")
    assert [r.episode_id for r in results] == [0, 1] and all(r.reproduced() for r in results), results
    # restoring the recorded state after every step: one-step errors only, but set_state itself perturbs PhysX
    # (contact caches are not part of the state), so contact-rich steps differ by up to a few millimetres
    results = replay_file(tmp_path / "demo", use_env_states=True)
    assert all(r.reproduced(pos_tol_m=5e-3) for r in results), results


def test_set_flat_env_state_restores_controller_targets(env):
    u = env.unwrapped
    layout = state_layout(env)
    ctrl = layout["controller/target_qpos"]
    env.reset(seed=0)
    rng = np.random.default_rng(2)
    for _ in range(3):
        env.step(rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
    saved = flat_env_state(env)
    for _ in range(3):
        env.step(rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
    assert np.abs(flat_env_state(env)[ctrl] - saved[ctrl]).max() > 1e-3  # the targets did move since
    u.set_state(torch.as_tensor(saved)[None])  # ManiSkill's own set_state would drop the controller part
    np.testing.assert_allclose(flat_env_state(env), saved, atol=1e-6)
    for _ in range(2):
        env.step(rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
    set_flat_env_state(env, saved, layout)
    np.testing.assert_allclose(flat_env_state(env), saved, atol=1e-6)


def test_bad_input_raises_typed_errors(tmp_path, env, episodes):
    ep = episodes[1]
    _write(tmp_path / "demo", env, ep)
    wide = Episode(**{**ep.__dict__, "action": np.zeros((ep.length, 27), np.float32)})
    other_task = Episode(**{**ep.__dict__, "task_id": "GenDex/OpenCabinet-v0"})
    with TrajectoryWriter(tmp_path / "demo", **env_info(env)) as w:
        with pytest.raises(EpisodeError, match="actions rows have 27 values"):
            w.add_episode(wide)
        with pytest.raises(EpisodeError, match="records GenDex/PickUpBottle-v0"):
            w.add_episode(other_task)
        assert w.episode_ids == [0]
    with pytest.raises(TrajectoryFileError, match="env_info"):
        TrajectoryWriter(tmp_path / "demo", **{**env_info(env), "max_episode_steps": 50})
    with pytest.raises(TrajectoryFileError, match="no episodes"):
        replay_episode(tmp_path / "demo.h5", 7)
    with h5py.File(tmp_path / "demo.h5", "a") as f:  # corrupt: one action row short of elapsed_steps
        actions = f["traj_0/actions"][()]
        del f["traj_0/actions"]
        f["traj_0"].create_dataset("actions", data=actions[:-1])
    with pytest.raises(TrajectoryFileError, match="elapsed_steps=12 but actions"):
        replay_episode(tmp_path / "demo.h5", 0)
    with h5py.File(tmp_path / "demo.h5", "a") as f:  # right length, wrong width for the env
        del f["traj_0/actions"]
        f["traj_0"].create_dataset("actions", data=np.zeros((12, 20), np.float32))
    with pytest.raises(ReplayError, match="actions of 20 values"):
        replay_episode(tmp_path / "demo.h5", 0)
    with h5py.File(tmp_path / "demo.h5", "a") as f:  # listed in the JSON but gone from the HDF5 file
        del f["traj_0"]
    with pytest.raises(TrajectoryFileError, match="lacks"):
        TrajectoryWriter(tmp_path / "demo", **env_info(env))
    assert issubclass(TrajectoryFileError, EpisodeError) and issubclass(ReplayError, EpisodeError)
