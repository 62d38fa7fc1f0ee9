"""TaskVersion: one owner of a version folder; atomic publishing; derived versions leave their source untouched."""

from __future__ import annotations

import json

import numpy as np
import pytest

from gendex_envs.errors import StageError, TaskNotFoundError, TaskSpecError
from gendex_envs.start_states import StartStates
from gendex_envs.task_version import (
    DRAFTS,
    Artifacts,
    PublishError,
    TaskLayout,
    TaskVersion,
    clean_drafts,
    derive_version,
    new_draft,
    publish,
    versions_in,
)


def _fake_policy(run: TaskLayout, stage: str) -> None:
    run.policies.mkdir(parents=True, exist_ok=True)
    run.policy(stage).write_bytes(b"zip")
    run.policy_record(stage).write_text(json.dumps({"format": 1, "stage": stage}))
    run.policy_curves(stage).mkdir(parents=True, exist_ok=True)
    (run.policy_curves(stage) / "progress.csv").write_text("a,b\n1,2\n")
    run.policy_checkpoints(stage).mkdir(parents=True, exist_ok=True)
    (run.policy_checkpoints(stage) / "x.zip").write_bytes(b"big")


def _states(stage: str) -> StartStates:
    return StartStates(stage=stage, state=np.zeros((2, 5), np.float32),
                       obj_reset_pos={"bottle": np.zeros((2, 3), np.float32)})


def test_a_version_knows_its_identity_spec_modules_and_judges(task_version):
    v = task_version("PutAppleBowl", 0)
    assert (v.name, v.version, v.env_id) == ("PutAppleBowl", 0, "GenDex/PutAppleBowl-v0")
    assert v.spec.name == "PutAppleBowl" and v.tasks_root == v.root.parent.parent
    assert v.reward().path == v.files.reward.resolve()
    assert v.reward("grasp_apple").path == v.files.stage_reward("grasp_apple").resolve()
    assert [p.name for p in v.files.reward_modules()][0] == v.files.reward.name
    assert v.files.module_stage(v.files.stage_reward("grasp_apple")) == "grasp_apple"
    assert v.files.module_stage(v.files.reward) is None
    task, grasp = v.judge(), v.judge("grasp_apple")
    assert task.conditions == v.spec.success.conditions and task.stage is None
    assert grasp.conditions == v.spec.stages[1].success and grasp.stage == "grasp_apple"
    assert v.judge(1) == grasp  # by index too
    with pytest.raises(StageError, match="Did you mean: 'grasp_apple'"):
        v.judge("grasp_aple")
    assert v.policy("grasp_apple") is None and v.start_states("grasp_apple") is None
    record = v.provenance()  # hand-written: no generation record, only the solvability gate's measurement
    assert set(record) == {"solvability"} and record["solvability"]["passed"] is True


def test_generated_versions_carry_their_provenance_and_renders(task_version):
    v = task_version("LiftApple", 0)
    assert v.provenance()["generation"]["backend"] == "offline"
    assert set(v.renders()) == {f"{w}_{view}" for w in ("before", "after")
                                for view in ("left_overhead", "right_overhead", "top_down")}


def test_a_folder_that_is_not_a_version_is_named(tmp_path):
    with pytest.raises(TaskNotFoundError, match="named v<N>"):
        TaskVersion.at(tmp_path / "Thing" / "latest")
    (tmp_path / "Thing" / "v0").mkdir(parents=True)
    with pytest.raises(TaskNotFoundError, match="holds no task spec"):
        TaskVersion.at(tmp_path / "Thing" / "v0")


def test_the_spec_name_must_match_the_folder(task_copy):
    copy = task_copy("PutAppleBowl", as_name="ScratchApple", register=False)
    copy.files.spec.write_text(copy.files.spec.read_text().replace("name: ScratchApple", "name: Other"))
    with pytest.raises(TaskSpecError, match="name 'Other' differs from its folder 'ScratchApple'"):
        _ = TaskVersion.at(copy.root).spec


def test_publish_is_atomic_and_takes_the_next_free_version(tmp_path, task_version):
    source = task_version("PickUpBottle", 0)
    root = tmp_path / "tasks"
    versions = []
    for _ in range(2):
        draft = new_draft(root)
        files = TaskLayout(draft)
        files.spec.write_text(source.files.spec.read_text())
        files.reward.write_text(source.files.reward.read_text())
        versions.append(publish(root, "PickUpBottle", draft, required=(files.spec, files.reward)))
    assert [v.version for v in versions] == [0, 1] and not list((root / DRAFTS).iterdir())
    assert [v.env_id for v in versions_in(root)] == ["GenDex/PickUpBottle-v0", "GenDex/PickUpBottle-v1"]
    draft = new_draft(root)
    with pytest.raises(PublishError, match="incomplete, not publishing it: missing"):
        publish(root, "PickUpBottle", draft, required=(TaskLayout(draft).spec,))
    assert len(versions_in(root)) == 2  # nothing half-written appeared
    assert clean_drafts(root) == 1 and not list((root / DRAFTS).iterdir())
    with pytest.raises(PublishError, match="not CamelCase"):
        publish(root, "pick_up", new_draft(root))


def test_derive_version_adds_policies_and_start_states_and_leaves_the_source_alone(task_copy, tmp_path):
    source = task_copy("PickUpBottle", as_name="ScratchBottle", register=False)
    before = source.file_digest()
    run = TaskLayout(tmp_path / "run")
    _fake_policy(run, "grasp_bottle")
    _states("lift_bottle").save(run.start_states("lift_bottle"))
    new = derive_version(source, [Artifacts(run.root)], {"command": "test"})
    assert (new.name, new.version) == ("ScratchBottle", 1)
    assert source.file_digest() == before and source.policy("grasp_bottle") is None
    assert new.policy("grasp_bottle") is not None and new.start_states("lift_bottle") is not None
    assert (new.files.policy_curves("grasp_bottle") / "progress.csv").is_file()
    assert not new.files.policy_checkpoints("grasp_bottle").exists()  # checkpoints stay in the run
    record = new.provenance()["promotion"]
    assert record["source"] == "GenDex/ScratchBottle-v0" and record["policies"] == ["grasp_bottle"]
    assert record["start_states"] == ["lift_bottle"] and record["command"] == "test"
    assert new.files.spec.read_bytes() == source.files.spec.read_bytes()


def test_derive_version_refuses_an_empty_run(task_copy, tmp_path):
    source = task_copy("PickUpBottle", as_name="ScratchBottle", register=False)
    with pytest.raises(StageError, match="nothing to promote"):
        derive_version(source, [Artifacts(tmp_path / "empty")], {})
    assert [v.version for v in versions_in(source.tasks_root)] == [0]


def test_file_digest_changes_with_any_file(task_copy):
    copy = task_copy("PickUpBottle", as_name="ScratchBottle", register=False)
    digest = copy.file_digest()
    copy.files.reward.write_text(copy.files.reward.read_text() + "\n")
    assert copy.file_digest() != digest
