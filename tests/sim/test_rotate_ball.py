"""RotateTennisBall: the palm_up keyframe, a stable scene, success = the declared rotation unless the ball left the
palm (the reward module's fail), random is not enough."""

import math

import numpy as np
import pytest
import torch
from mani_skill.utils.structs import Pose

from gendex_envs.agents.ur10e_shadow import ARM_JOINTS, KEYFRAME_QPOS_BY_NAME
from gendex_envs.geometry import quat_mul, quat_rotate, yaw_quat
from generator.steps.validate import check_reward_source

TASK = "GenDex/RotateTennisBall-v0"
BALL_RADIUS_M = 0.0335 * 0.97


def _make(make_env):
    return make_env(TASK, control_mode="pd_joint_delta_pos", control_joint="hand")


def test_reward_module_passes_the_validator(task_version):
    check_reward_source(task_version("RotateTennisBall", 0).files.reward.read_text())


def test_palm_up_keyframe_faces_up_and_clears_the_table(make_env):
    env = _make(make_env)
    env.reset(seed=0)
    agent = env.unwrapped.agent
    palm = agent.palm_link.pose
    normal = quat_rotate(palm.q, torch.tensor([[0.0, -1.0, 0.0]]))[0]  # -y of the palm frame points out of the palm
    fingers = quat_rotate(palm.q, torch.tensor([[0.0, 0.0, 1.0]]))[0]
    assert normal[2].item() > 0.999 and fingers[0].item() > 0.999
    assert 0.25 <= palm.p[0, 2].item() <= 0.35
    for link in agent.robot.get_links():  # links (not the base, standing on the table top) clear the table
        if link.name in ("base_link", "shoulder_link") or not link._objs[0].collision_shapes:
            continue
        assert link._objs[0].compute_global_aabb_tight()[0][2] > 0.05, link.name
    assert set(KEYFRAME_QPOS_BY_NAME["palm_up"]) >= set(ARM_JOINTS)


def test_ball_rests_in_the_palm_under_zero_actions(make_env):
    env = _make(make_env)
    env.reset(seed=0)
    zero = np.zeros(env.action_space.shape, dtype=np.float32)
    for _ in range(100):
        _, _, terminated, _, info = env.step(zero)
        assert not terminated
    assert not info["fail"] and abs(math.degrees(info["rotation"])) < 20.0 and info["palm_dist"] < 0.04


def _place_ball(u, yaw_rad: float, shift_m: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> None:
    """Turn the ball about its own centre by ``yaw_rad`` about world z and shift it."""
    ball = u.obj("ball")
    p, q = ball.pose.p, ball.pose.q
    up = torch.tensor([[0.0, 0.0, BALL_RADIUS_M]])
    centre = p + quat_rotate(q, up)
    q_new = quat_mul(yaw_quat(torch.tensor([yaw_rad])), q)
    p_new = centre - quat_rotate(q_new, up) + torch.tensor([shift_m])
    ball.set_pose(Pose.create_from_pq(p_new, q_new))


def test_success_is_the_declared_rotation_vetoed_by_a_drop(make_env):
    env = _make(make_env)
    u = env.unwrapped
    assert [c.type for c in u.judge.conditions] == ["rotated"]
    env.reset(seed=0)
    info = u.judge.evaluate(u)
    assert not info["success"].item() and not info["fail"].item()
    _place_ball(u, math.radians(100.0))
    info = u.judge.evaluate(u)
    assert info["success"].item() and not info["fail"].item()
    assert math.degrees(info["rotation"].item()) == pytest.approx(100.0, abs=1.0)
    _place_ball(u, math.radians(-200.0))  # back to -100 degrees: the wrong sense is no success
    assert not u.judge.evaluate(u)["success"].item()
    env.reset(seed=0)
    _place_ball(u, math.radians(100.0), shift_m=(0.1, 0.0, 0.0))  # turned, but out of the palm
    info = u.judge.evaluate(u)
    assert info["fail"].item() and not info["success"].item()
    assert bool(u.spec_success().item())  # the rotation condition holds; the module's fail vetoes success


def test_random_policy_rarely_succeeds(make_env):
    env = _make(make_env)
    env.action_space.seed(0)
    successes = 0
    for seed in range(5):
        env.reset(seed=seed)
        for _ in range(60):
            _, reward, terminated, truncated, info = env.step(env.action_space.sample())
            assert np.isfinite(reward)
            if terminated or truncated:
                break
        successes += bool(info["success"])
    assert successes <= 2


def test_trained_policy_turns_the_ball_under_the_executor(make_env):
    """v1's policy (v0's refined under less exploration noise) as ``gendex collect`` runs it: it acts until the quarter
    turn has held the task's 5 steps, as in the stage env it was trained in, so the task succeeds on its last step."""
    from gendex.solve.attempt import run_attempt
    from gendex.solve.executor import StageExecutor

    env = make_env("GenDex/RotateTennisBall-v1", control_mode="pd_joint_pos", control_joint="both")
    executor = StageExecutor()
    successes = 0
    for seed in range(5):
        outcome = run_attempt(env, executor, seed)
        successes += outcome.succeeded
        if outcome.succeeded:
            assert [(log.stage, log.primitive) for log in executor.logs] == [("rotate_ball", "policy")]
            assert executor.logs[0].steps == outcome.steps
    assert successes >= 4


def test_benchmark_reports_the_failure_kinds(repo_root):
    import re
    import subprocess
    import sys

    script = repo_root / "benchmarks" / "rotate_ball.py"
    out = subprocess.run([sys.executable, str(script), "--task", "GenDex/RotateTennisBall-v0", "--episodes", "2",
                          "--seed", "5", "--policies", "ppo", "executor"], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    rows = re.findall(r"^(ppo|executor)\s+success\s+(\d+)/2\s+drop\s+(\d+)\s+short\s+(\d+)\s+lost\s+(\d+)", out.stdout,
                      re.MULTILINE)
    assert [r[0] for r in rows] == ["ppo", "executor"], out.stdout
    for _, *counts in rows:
        assert sum(map(int, counts)) == 2
    assert rows[0][1:] == rows[1][1:]  # the executor runs the policy as its stage env does
    failed = sum(int(n) for n in rows[0][2:])
    assert len(re.findall(r"^    seed \d+: (?:drop|short|lost) ", out.stdout, re.MULTILINE)) == 2 * failed
