"""PPO's ``paper`` preset on ManiSkill's GPU backend (many sub-scenes, one process). Marked ``gpu``: needs CUDA.

Run on a machine with an NVIDIA GPU: ``.venv/bin/pytest -m gpu tests/gpu``. Not run on the development machine.
"""

import dataclasses

import pytest
import torch

pytestmark = pytest.mark.gpu
if not torch.cuda.is_available():
    pytest.skip("ManiSkill's GPU backend needs a CUDA device; none here", allow_module_level=True)

from generator.rl.presets import PRESETS  # noqa: E402
from generator.rl.train import train_stage  # noqa: E402


def test_paper_preset_trains_a_stage_with_start_states(tmp_path):
    preset = dataclasses.replace(PRESETS["paper"], n_envs=64, batch_size=512, net_arch=(256, 256))
    r = train_stage("generated_tasks/PickUpBottle/v0", "grasp_bottle", steps=64 * 16 * 4, preset=preset,
                    policy_dir=tmp_path / "policies", eval_episodes=2, progress=False)
    assert r.policy_path.is_file() and r.steps >= 64 * 16 * 4
    assert (tmp_path / "start_states" / "grasp_bottle.npz").is_file()
