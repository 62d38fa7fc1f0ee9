"""Task discovery and registration into a scratch registry, and the errors of bad task folders."""

import shutil

import gymnasium as gym
import pytest

from gendex_envs.errors import DuplicateTaskError, RewardModuleError, TaskNotFoundError, TaskSpecError
from gendex_envs.registry import REPO_TASKS_DIR, discover_tasks, register_tasks, task_entry
from gendex_envs.reward_module import load_reward_module

SEED = REPO_TASKS_DIR / "PutAppleBowl" / "v0"


@pytest.fixture
def scratch_root(tmp_path):
    """A task root holding a copy of PutAppleBowl as 'ScratchApple' v3; its ids are removed afterwards."""
    folder = tmp_path / "tasks" / "ScratchApple" / "v3"
    shutil.copytree(SEED, folder)
    text = (folder / "task.yaml").read_text().replace("name: PutAppleBowl", "name: ScratchApple")
    (folder / "task.yaml").write_text(text)
    yield tmp_path / "tasks"
    for env_id in [k for k in gym.registry if k.startswith("GenDex/Scratch")]:
        del gym.registry[env_id]


def test_seed_tasks_are_discovered_with_versions():
    found = discover_tasks([REPO_TASKS_DIR])
    assert {"GenDex/OpenCabinet-v0", "GenDex/PickUpBottle-v0", "GenDex/PutAppleBowl-v0"} <= set(found)
    entry = found["GenDex/PutAppleBowl-v0"]
    assert entry.name == "PutAppleBowl" and entry.version == 0 and entry.task_dir == SEED


def test_register_scratch_root_and_make(scratch_root):
    assert register_tasks([scratch_root]) == ["GenDex/ScratchApple-v3"]
    assert register_tasks([scratch_root]) == []  # same folder again: no-op
    assert task_entry("GenDex/ScratchApple-v3").task_dir == scratch_root / "ScratchApple" / "v3"
    env = gym.make("GenDex/ScratchApple-v3")
    try:
        assert env.unwrapped.task_spec.name == "ScratchApple"
    finally:
        env.close()


def test_same_id_from_another_folder_is_a_duplicate(scratch_root, tmp_path):
    register_tasks([scratch_root])
    other = tmp_path / "other"
    shutil.copytree(scratch_root, other)
    with pytest.raises(DuplicateTaskError, match="GenDex/ScratchApple-v3.*already registered"):
        register_tasks([other])
    assert register_tasks([other], override=True) == ["GenDex/ScratchApple-v3"]
    assert task_entry("GenDex/ScratchApple-v3").task_dir == other / "ScratchApple" / "v3"


def test_unknown_task_id_suggests_close_ones():
    with pytest.raises(TaskNotFoundError, match="PutAppleBowl-v0"):
        task_entry("GenDex/PutAppleBowel-v0")


def test_missing_task_root_is_an_error(tmp_path):
    with pytest.raises(TaskNotFoundError, match="not a folder"):
        discover_tasks([tmp_path / "nope"])


def test_unknown_asset_in_yaml_raises_named_error(scratch_root):
    task_yaml = scratch_root / "ScratchApple" / "v3" / "task.yaml"
    task_yaml.write_text(task_yaml.read_text().replace("asset: apple", "asset: appel"))
    register_tasks([scratch_root])
    with pytest.raises(TaskSpecError) as err:
        gym.make("GenDex/ScratchApple-v3")
    message = str(err.value)
    assert str(task_yaml) in message and "objects[0].asset" in message and "'appel'" in message
    assert "'apple'" in message  # suggestion


def test_reward_module_without_evaluate_is_rejected(tmp_path):
    path = tmp_path / "reward.py"
    path.write_text("def compute_dense_reward(env, obs, action, info):\n    return 0\n")
    with pytest.raises(RewardModuleError, match="lacks \\['evaluate'\\]"):
        load_reward_module(path)


def test_reward_module_that_fails_to_import_is_reported(tmp_path):
    path = tmp_path / "reward.py"
    path.write_text("import not_a_module_anywhere\n")
    with pytest.raises(RewardModuleError, match="failed to import: ModuleNotFoundError"):
        load_reward_module(path)
    with pytest.raises(RewardModuleError, match="does not exist"):
        load_reward_module(tmp_path / "missing.py")
