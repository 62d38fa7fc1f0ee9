"""GPU backend: many envs in one process. Marked ``gpu``: the default test command deselects it (no CUDA on CI).

Run on a machine with an NVIDIA GPU: ``.venv/bin/pytest -m gpu tests/gpu``.
"""

import gymnasium as gym
import pytest
import torch

from gendex_envs.registry import REFERENCE_TASKS as REFERENCE_NAMES

pytestmark = pytest.mark.gpu
if not torch.cuda.is_available():
    pytest.skip("ManiSkill's GPU backend needs a CUDA device; none here", allow_module_level=True)

REFERENCE_TASKS = tuple(f"GenDex/{name}-v0" for name in REFERENCE_NAMES)  # version 0 of each reference task
NUM_ENVS = 8


@pytest.mark.parametrize("env_id", REFERENCE_TASKS)
def test_batched_reward_and_partial_reset(env_id):
    env = gym.make(env_id, num_envs=NUM_ENVS, sim_backend="physx_cuda", control_mode="pd_joint_delta_pos")
    try:
        u = env.unwrapped
        env.reset(seed=list(range(NUM_ENVS)))
        for _ in range(5):
            obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        assert reward.shape == (NUM_ENVS,) and torch.isfinite(reward).all()
        assert info["success"].shape == (NUM_ENVS,) and info["success"].dtype == torch.bool
        assert u.agent.get_hand_group_obj_mean_force(next(iter(u.objects.values()))).shape == (NUM_ENVS, 6, 1)
        # partial reset: the other envs keep their state and step counters
        keep = torch.arange(1, NUM_ENVS, device=u.device)
        before = u.agent.robot.get_qpos()[keep].clone()
        steps_before = u.elapsed_steps[keep].clone()
        env.reset(options={"env_idx": torch.tensor([0], device=u.device)})
        torch.testing.assert_close(u.agent.robot.get_qpos()[keep], before)
        assert (u.elapsed_steps[keep] == steps_before).all() and u.elapsed_steps[0] == 0
    finally:
        env.close()
