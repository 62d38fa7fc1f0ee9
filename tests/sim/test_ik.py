"""ArmIK: recovers reachable palm poses within limits, refuses unreachable ones."""

import numpy as np
import pytest
import sapien

from gendex.solve.ik import ArmIK


@pytest.fixture(scope="module")
def ik():
    import gymnasium as gym

    import gendex_envs  # noqa: F401

    env = gym.make("GenDex/PickUpBottle-v0")
    env.reset(seed=0)
    solver = ArmIK(env.unwrapped.agent)
    solver.q_rest = env.unwrapped.agent.robot.get_qpos()[0].numpy().astype(np.float64)
    yield solver
    env.close()


@pytest.mark.parametrize("seed", range(5))
def test_reachable_poses_are_recovered(ik, seed):
    rng = np.random.default_rng(seed)
    q = ik.q_rest.copy()
    q[ik.arm] += rng.uniform(-0.6, 0.6, 6)  # a nearby reachable configuration
    target = ik.fk(q)
    found = ik.solve(target, ik.q_rest, seed=seed)
    assert found is not None
    got = ik.fk(found)
    assert np.linalg.norm(got.p - target.p) < 1e-3
    assert abs(abs(float(np.dot(got.q, target.q))) - 1.0) < 1e-4
    assert np.all(found[ik.arm] >= ik.limits[ik.arm, 0]) and np.all(found[ik.arm] <= ik.limits[ik.arm, 1])
    np.testing.assert_array_equal(np.delete(found, ik.arm), np.delete(ik.q_rest, ik.arm))


def test_unreachable_pose_returns_none(ik):
    far = sapien.Pose(p=[2.5, 0.0, 0.3])
    assert ik.solve(far, ik.q_rest, restarts=4) is None
