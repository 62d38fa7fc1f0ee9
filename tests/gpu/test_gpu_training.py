"""PPO's ``paper`` preset on ManiSkill's GPU backend (many sub-scenes, one process). Marked ``gpu``: needs CUDA.

Run on a machine with an NVIDIA GPU: ``.venv/bin/pytest -m gpu tests/gpu``. Not run on the development machine.
"""

import dataclasses

import pytest
import torch

pytestmark = pytest.mark.gpu
if not torch.cuda.is_available():
    pytest.skip("ManiSkill's GPU backend needs a CUDA device; none here", allow_module_level=True)

from gendex.train.presets import PRESETS  # noqa: E402
from gendex.train.train import train_stage  # noqa: E402
from gendex_envs.task_version import TaskLayout  # noqa: E402


def test_paper_preset_trains_a_stage_with_start_states(task_version, tmp_path):
    preset = dataclasses.replace(PRESETS["paper"], n_envs=64, batch_size=512, net_arch=(256, 256))
    run = tmp_path / "run"
    r = train_stage(task_version("PickUpBottle", 0), "grasp_bottle", steps=64 * 16 * 4, preset=preset, run_dir=run,
                    eval_episodes=2, progress=False)
    assert r.policy.model.is_file() and r.steps >= 64 * 16 * 4
    assert TaskLayout(run).start_states("grasp_bottle").is_file()
