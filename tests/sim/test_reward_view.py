"""Reward code gets a read-only view of the env, not the env: writes into what it reads change nothing the simulator
or the env's judgement depends on, and it holds no handle that acts (issue 17's capability-only reward API).

These modules are loaded straight into an env, without the static check that would reject them first: the point is
that the view makes mutation impossible even for code that got past it."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from gendex_envs.reward_view import EntityView, PoseView, RewardView, view_of
from gendex_envs.task_env import TaskEnv

HONEST = '''
import torch
from gendex_envs import reward_terms as rt


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device),
            "apple_height": env.obj_height("apple")}


def compute_dense_reward(env, obs, action, info):
    return rt.reach(torch.linalg.norm(env.palm_pose.p - env.obj_pose("apple").p, dim=-1))
'''

# Each writes into every tensor it is handed or can read, then returns the honest values.
VANDAL = '''
import torch
from gendex_envs import reward_terms as rt


def evaluate(env):
    env.obj_pose("apple").p.add_(0.5)                  # lift the apple "in place"
    env.obj_pose("bowl").p[:] = 0.0
    env.init_obj_pos("apple")[:, 2] -= 1.0             # fake a lift: lower the recorded start height
    env.palm_pose.p.mul_(0.0)
    env.tip_positions.zero_()
    env.agent.robot.get_qpos().fill_(1.0)              # overwrite the arm targets through a returned tensor
    env.agent.get_hand_group_obj_mean_force(env.obj("apple")).fill_(100.0)
    env.obj("apple").linear_velocity.fill_(50.0)       # launch it
    env.spec_success().fill_(True)
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device),
            "apple_height": env.obj_height("apple")}


def compute_dense_reward(env, obs, action, info):
    info["success"].fill_(True)                        # declare success
    info["fail"].fill_(False)
    action.fill_(1.0)
    if isinstance(obs, torch.Tensor):
        obs.fill_(0.0)
    return rt.reach(torch.linalg.norm(env.palm_pose.p - env.obj_pose("apple").p, dim=-1))
'''


@pytest.fixture
def unchecked(monkeypatch):
    """Untrusted folders are statically checked on load, which would refuse the vandal; skip it, as code that got
    past the check would."""
    import gendex_envs.reward_module

    checker = next(n for n in ("check_reward_source", "check_reward_file") if hasattr(gendex_envs.reward_module, n))
    monkeypatch.setattr(gendex_envs.reward_module, checker, lambda *args: None)


def _rollout(task_copy, source: str, name: str, steps: int = 25):
    version = task_copy("PutAppleBowl", as_name=name, register=False)
    version.files.reward.write_text(source)
    env = TaskEnv(task=version.root, obs_mode="state", control_mode="pd_joint_delta_pos", render_backend="none")
    try:
        obs, _ = env.reset(seed=11)
        rng = np.random.default_rng(0)
        rows = []
        for _ in range(steps):
            action = torch.as_tensor(rng.uniform(-1, 1, env.action_space.shape), dtype=torch.float32)
            obs, reward, _, _, info = env.step(action)
            rows.append((env.obj_pose("apple").p.clone(), env.obj_pose("bowl").p.clone(),
                         env.agent.robot.get_qpos().clone(), env.init_obj_pos("apple").clone(),
                         info["success"].clone(), reward.clone(), obs.clone()))
        return rows
    finally:
        env.close()


def test_writes_through_the_view_change_nothing_the_env_keeps_or_decides(task_copy, unchecked, monkeypatch):
    # what is checked is isolation, not time: a call of 28 ms overran the 5 s per-call limit once on a 2-core
    # machine running the whole suite in two processes (a clean-clone run, 2026-12-01)
    monkeypatch.setenv("GENDEX_SANDBOX_TIMEOUT_S", "60")
    honest = _rollout(task_copy, HONEST, "ViewHonest")
    vandal = _rollout(task_copy, VANDAL, "ViewVandal")
    for step, (a, b) in enumerate(zip(honest, vandal, strict=True)):
        for what, x, y in zip(("apple", "bowl", "qpos", "reset pose", "success", "reward", "obs"), a, b, strict=True):
            assert torch.equal(x, y), f"step {step}: {what} differs after the module wrote into its view"
    assert not any(bool(row[4].any()) for row in vandal)  # nothing declared success


@pytest.fixture(scope="module")
def env():
    from gendex_envs.registry import resolve_task

    e = TaskEnv(task=resolve_task("GenDex/OpenCabinet-v1"), obs_mode="state", render_backend="none")
    e.reset(seed=0)
    yield e
    e.close()


def test_the_view_offers_the_documented_members_and_no_handles(env):
    view = view_of(env)
    assert isinstance(view, RewardView) and view is view_of(env)
    assert view.num_envs == 1 and view.device == torch.device(env.device) and view.table_height == env.table_height
    assert isinstance(view.obj_pose("cabinet"), PoseView) and view.obj_pose("cabinet").raw_pose.shape == (1, 7)
    assert view.palm_pose.p.shape == (1, 3) and view.tip_positions.shape == (1, 5, 3)
    assert view.joint_qpos("cabinet").shape == (1,) and view.handle_pos("cabinet").shape == (1, 3)
    handle = view.handle_link("cabinet")
    assert isinstance(handle, EntityView)
    forces = view.agent.get_hand_group_obj_mean_force(handle)
    assert forces.shape == (1, 6, 1)
    assert torch.equal(forces[..., 0], env.hand_forces("cabinet", "handle"))
    assert view.agent.robot.get_qpos().shape == (1, 30)
    # nothing that acts is reachable by a public name
    for holder, names in ((view, ("scene", "unwrapped", "step", "reset", "task_spec", "objects", "articulations",
                                  "judge", "set_state", "goal_site", "_env")),
                          (view.agent, ("controller", "set_control_mode", "palm_link", "contacts")),
                          (view.agent.robot, ("set_qpos", "set_pose", "links", "set_drive_targets")),
                          (handle, ("set_pose", "set_qpos", "set_linear_velocity", "entity", "_entity_obj"))):
        for name in names:
            assert not hasattr(holder, name), f"{type(holder).__name__}.{name} is reachable"
    assert not hasattr(view, "__dict__")


def test_views_are_read_only_and_name_what_is_wrong(env):
    view = view_of(env)
    for target, attr in ((view, "num_envs"), (view, "obj_pose"), (view.agent, "robot"),
                         (view.obj("cabinet"), "name"), (view.agent.robot, "anything")):
        with pytest.raises(AttributeError, match="read-only"):
            setattr(target, attr, 1)
    from gendex_envs.errors import TaskSpecError

    with pytest.raises(TaskSpecError, match="no object 'apple'"):
        view.obj_pose("apple")
    with pytest.raises(TaskSpecError, match="no object 'apple'"):
        view.handle_link("apple")
    with pytest.raises(TypeError, match="env.obj"):
        view.agent.get_hand_group_obj_mean_force(env.obj("cabinet"))  # a real entity is not accepted
