"""Task discovery and registration into a scratch registry, unversioned names, and the errors of bad task folders."""

import gymnasium as gym
import pytest

from gendex_envs.errors import DuplicateTaskError, RewardModuleError, TaskNotFoundError, TaskSpecError
from gendex_envs.registry import REFERENCE_TASKS, REPO_TASKS_DIR, discover_tasks, register_tasks, resolve_task
from gendex_envs.reward_module import load_reward_module
from gendex_envs.task_version import TaskLayout


def test_reference_tasks_are_discovered_with_versions(task_version):
    found = discover_tasks([REPO_TASKS_DIR])
    assert {f"GenDex/{name}-v0" for name in REFERENCE_TASKS} <= set(found)
    version = found["GenDex/PutAppleBowl-v0"]
    assert version.name == "PutAppleBowl" and version.version == 0
    assert version == task_version("PutAppleBowl", 0)


def test_register_scratch_root_and_make(task_copy):
    copy = task_copy("PutAppleBowl", as_name="ScratchApple", version=3, register=False)
    root = copy.tasks_root
    assert register_tasks([root]) == ["GenDex/ScratchApple-v3"]
    try:
        assert register_tasks([root]) == []  # same folder again: no-op
        assert resolve_task("GenDex/ScratchApple-v3").root == copy.root
        env = gym.make("GenDex/ScratchApple-v3")
        try:
            assert env.unwrapped.task_spec.name == "ScratchApple"
            assert env.unwrapped.task == copy
        finally:
            env.close()
    finally:
        from gendex_envs.registry import unregister_tasks

        unregister_tasks(["GenDex/ScratchApple-v3"])


def test_every_version_registers_and_unversioned_names_take_the_highest(task_copy):
    task_copy("PutAppleBowl", as_name="ScratchApple", version=0)
    newest = task_copy("PutAppleBowl", as_name="ScratchApple", version=2)
    assert {"GenDex/ScratchApple-v0", "GenDex/ScratchApple-v2"} <= set(gym.registry)
    assert resolve_task("ScratchApple") == newest
    assert resolve_task("GenDex/ScratchApple") == newest
    with pytest.warns(UserWarning, match="latest versioned environment `GenDex/ScratchApple-v2`"):
        env = gym.make("GenDex/ScratchApple")  # Gymnasium resolves it the same way
    try:
        assert env.unwrapped.task == newest
    finally:
        env.close()


def test_same_id_from_another_folder_is_a_duplicate(task_copy, tmp_path):
    import shutil

    copy = task_copy("PutAppleBowl", as_name="ScratchApple", version=3)
    other = tmp_path / "other"
    shutil.copytree(copy.tasks_root, other)
    with pytest.raises(DuplicateTaskError, match="GenDex/ScratchApple-v3.*already registered"):
        register_tasks([other])
    assert register_tasks([other], override=True) == ["GenDex/ScratchApple-v3"]
    assert resolve_task("GenDex/ScratchApple-v3").root == other / "ScratchApple" / "v3"


def test_unknown_task_id_suggests_close_ones():
    with pytest.raises(TaskNotFoundError, match="PutAppleBowl-v0"):
        resolve_task("GenDex/PutAppleBowel-v0")


def test_missing_task_root_is_an_error(tmp_path):
    with pytest.raises(TaskNotFoundError, match="not a folder"):
        discover_tasks([tmp_path / "nope"])


def test_unknown_asset_in_yaml_raises_named_error(task_copy):
    copy = task_copy("PutAppleBowl", as_name="ScratchApple", version=3)
    task_yaml = copy.files.spec
    task_yaml.write_text(task_yaml.read_text().replace("asset: apple", "asset: appel"))
    with pytest.raises(TaskSpecError) as err:
        gym.make("GenDex/ScratchApple-v3")
    message = str(err.value)
    assert str(task_yaml) in message and "objects[0].asset" in message and "'appel'" in message
    assert "'apple'" in message  # suggestion


def test_a_broken_version_is_skipped_with_a_logged_reason(task_copy, caplog):
    copy = task_copy("PutAppleBowl", as_name="ScratchApple", version=1, register=False)
    copy.files.spec.write_text(copy.files.spec.read_text().replace("skill: reach", "skill: teleport"))
    try:
        assert register_tasks([copy.tasks_root]) == []
        assert "not registering GenDex/ScratchApple-v1" in caplog.text and "'teleport'" in caplog.text
    finally:
        assert "GenDex/ScratchApple-v1" not in gym.registry


def test_reward_module_without_evaluate_is_rejected(tmp_path):
    path = TaskLayout(tmp_path).reward
    path.write_text("def compute_dense_reward(env, obs, action, info):\n    return 0\n")
    with pytest.raises(RewardModuleError, match="lacks \\['evaluate'\\]"):
        load_reward_module(path, trusted=True)
    # from a folder that is not the repository's, the static check refuses it before it is imported
    with pytest.raises(RewardModuleError, match="static check rejected it(.|\n)*no top-level function `evaluate"):
        load_reward_module(path)


def test_reward_module_that_fails_to_import_is_reported(tmp_path):
    path = TaskLayout(tmp_path).reward
    path.write_text("import not_a_module_anywhere\n")
    with pytest.raises(RewardModuleError, match="failed to import: ModuleNotFoundError"):
        load_reward_module(path, trusted=True)
    with pytest.raises(RewardModuleError, match="does not exist"):
        load_reward_module(tmp_path / "missing.py")
