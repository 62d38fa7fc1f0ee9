"""UR10eShadowHand in the simulator: keyframes, holding still, frozen joints per control mode, coupling, API shapes."""

import numpy as np
import pytest
import torch

from gendex_envs.agents.ur10e_shadow import (
    ALL_JOINTS,
    CONTROL_JOINT_GROUPS,
    COUPLED_DISTAL,
    KEYFRAME_QPOS_BY_NAME,
)
from gendex_envs.assets.catalog import get_asset

TASK = "GenDex/PickUpBottle-v0"


def _joint_index(agent) -> dict[str, int]:
    return {j.name: i for i, j in enumerate(agent.robot.get_active_joints())}


def test_keyframes_match_robot_dof(make_env):
    agent = make_env(TASK).unwrapped.agent
    assert agent.robot.dof == len(ALL_JOINTS) == 30
    for name, keyframe in agent.keyframes.items():
        assert keyframe.qpos.shape == (30,), name
        assert set(KEYFRAME_QPOS_BY_NAME[name]) == set(ALL_JOINTS), name
        limits = agent.robot.get_qlimits()[0].cpu().numpy()
        assert np.all(keyframe.qpos >= limits[:, 0] - 1e-6) and np.all(keyframe.qpos <= limits[:, 1] + 1e-6), name


@pytest.mark.parametrize("keyframe", ["rest", "pregrasp_open", "palm_up"])
def test_hand_holds_keyframe(make_env, keyframe):
    env = make_env(TASK, control_mode="pd_joint_delta_pos")
    agent = env.unwrapped.agent
    env.reset(seed=0)
    q0 = torch.as_tensor(agent.keyframes[keyframe].qpos)
    agent.robot.set_qpos(q0[None])
    agent.controller.reset()
    zero = np.zeros(env.action_space.shape, dtype=np.float32)
    for _ in range(200):
        env.step(zero)
    drift = (agent.robot.get_qpos()[0] - q0).abs().max().item()
    assert drift < 0.02, f"joint drift {drift:.4f} rad over 200 control steps"


@pytest.mark.parametrize("mode", sorted(CONTROL_JOINT_GROUPS))
def test_frozen_joints_hold_under_random_actions(make_env, mode):
    env = make_env(TASK, control_mode="pd_joint_delta_pos", control_joint=mode)
    agent = env.unwrapped.agent
    env.reset(seed=1)
    env.action_space.seed(1)
    free = set(CONTROL_JOINT_GROUPS[mode])
    free |= {f for f, leader in COUPLED_DISTAL.items() if leader in free}
    expected_dim = len([j for j in CONTROL_JOINT_GROUPS[mode] if j not in COUPLED_DISTAL])
    assert env.action_space.shape == (expected_dim,)
    idx = _joint_index(agent)
    frozen = [idx[j] for j in ALL_JOINTS if j not in free]
    moving = [idx[j] for j in free]
    q0 = agent.robot.get_qpos()[0].clone()
    for _ in range(40):
        env.step(env.action_space.sample())
    q = agent.robot.get_qpos()[0]
    if frozen:
        assert (q[frozen] - q0[frozen]).abs().max().item() < 0.01
    assert (q[moving] - q0[moving]).abs().max().item() > 0.05, "free joints should move under random actions"


def test_distal_joints_follow_middle_joints(make_env):
    env = make_env(TASK, control_mode="pd_joint_pos", control_joint="hand")
    agent = env.unwrapped.agent
    env.reset(seed=0)
    controller = agent.controller
    action = controller.free_targets()[0].cpu().numpy().copy()
    names = controller.free_joint_names
    for leader in COUPLED_DISTAL.values():
        action[names.index(leader)] = 0.9
    for _ in range(30):
        env.step(action)
    q, idx = agent.robot.get_qpos()[0], _joint_index(agent)
    for follower, leader in COUPLED_DISTAL.items():
        assert q[idx[leader]].item() > 0.6
        assert q[idx[follower]].item() == pytest.approx(q[idx[leader]].item(), abs=0.1)


def test_reward_api_shapes(make_env):
    env = make_env(TASK)
    env.reset(seed=0)
    u = env.unwrapped
    agent, bottle = u.agent, u.obj("bottle")
    assert agent.tip_poses.shape == (1, 35)
    assert len(agent.tip_links) == 5 and agent.palm_link.name == "palm"
    for value in (agent.get_fsr_impulse(), agent.get_fsr_force(), agent.get_fsr_obj_force(bottle),
                  agent.get_fsr_obj_impulse(bottle)):
        assert value.shape == (1, 5, 3) and torch.isfinite(value).all()
    assert agent.get_hand_group_obj_mean_force(bottle).shape == (1, 6, 1)
    # tip points lie 2.6-2.75 cm out along each distal link
    tips = agent.tip_positions[0]
    links = torch.stack([link.pose.p[0] for link in agent.tip_links])
    dist = torch.linalg.norm(tips - links, dim=-1)
    torch.testing.assert_close(dist, torch.tensor([0.0275, 0.026, 0.026, 0.026, 0.026]), atol=1e-5, rtol=0)


def _push_bottle(env, target_p: torch.Tensor, steps: int = 12) -> tuple[torch.Tensor, torch.Tensor]:
    """Hold the (weightless) bottle's top just under ``target_p`` and push it up at 5 cm/s every step.

    Returns the largest fingertip force [5] and hand-group force [6] on the bottle seen meanwhile.
    """
    u = env.unwrapped
    bottle = u.obj("bottle")
    bottle._bodies[0].disable_gravity = True
    pose = bottle.pose
    p = target_p.clone()[None]
    p[0, 2] -= get_asset("bottle").size_m[2] + 0.004  # the origin is at the bottle's base
    bottle.set_pose(type(pose).create_from_pq(p, pose.q))
    hold = u.agent.controller.free_targets()[0].cpu().numpy()
    tips, groups = torch.zeros(5), torch.zeros(6)
    for _ in range(steps):
        bottle.set_linear_velocity(torch.tensor([[0.0, 0.0, 0.05]]))
        env.step(hold)
        tips = torch.maximum(tips, torch.linalg.norm(u.agent.get_fsr_obj_force(bottle)[0], dim=-1))
        groups = torch.maximum(groups, u.agent.get_hand_group_obj_mean_force(bottle)[0, :, 0])
    return tips, groups


def test_fingertip_contact_force_is_measured(make_env):
    """Pushing the bottle up into the index fingertip registers force on that fingertip, not on the others."""
    env = make_env(TASK, control_mode="pd_joint_pos", control_joint="hand")
    env.reset(seed=0)
    tips, groups = _push_bottle(env, env.unwrapped.agent.tip_positions[0, 1])
    assert tips[1] > 0.05, f"index fingertip force {tips}"
    assert tips[[0, 3, 4]].max() < 0.05, f"fingertips far from the bottle report force: {tips}"
    assert groups[1] > 0 and groups[5] == 0, f"group forces {groups}"


def test_palm_contact_force_is_measured(make_env):
    env = make_env(TASK, control_mode="pd_joint_pos", control_joint="hand")
    env.reset(seed=0)
    palm = env.unwrapped.agent.palm_link.pose.p[0].clone()
    palm[2] -= 0.012  # just below the palm's collision boxes
    tips, groups = _push_bottle(env, palm)
    assert groups[5] > 0.05, f"palm group force {groups}"
