"""Success that asks for the hand's work first (:mod:`generator.steps.approach`): which tasks get which first step,
the spec rewrite that keeps every other byte, and publishing it as a task's next version."""

from __future__ import annotations

import json
import shutil

import pytest
import yaml

from gendex_envs.registry import REPO_TASKS_DIR as TASKS
from gendex_envs.spec import load_task_spec, parse_task_spec
from gendex_envs.task_version import TaskVersion
from generator.steps.approach import (
    APPROACH_M,
    APPROACH_STEPS,
    NothingToHarden,
    first_steps,
    publish_worked_by_hand,
    replace_success,
    worked_by_hand,
)


def version(env_id: str) -> TaskVersion:
    name, v = env_id.removeprefix("GenDex/").rsplit("-v", 1)
    return TaskVersion.at(TASKS / name / f"v{v}")


def test_a_door_task_first_needs_the_fingers_at_its_handle():
    spec = worked_by_hand(version("GenDex/CloseCabinet-v3").spec)
    (step,) = spec.success.sequence
    (c,) = step.conditions
    assert (c.type, c.object, c.part, c.max_dist_m) == ("fingertips_near", "cabinet", "handle", APPROACH_M)
    assert step.hold_steps == APPROACH_STEPS
    assert spec.success.conditions == version("GenDex/CloseCabinet-v3").spec.success.conditions


def test_a_placement_the_plan_grasps_first_needs_the_object_held():
    (step,) = first_steps(version("GenDex/SetBaseballFar-v1").spec)
    (c,) = step.conditions
    assert (c.type, c.object, c.negate) == ("grasped", "baseball", False)


def test_a_composed_task_gets_its_steps_in_the_plans_order():
    spec = version("GenDex/CloseBoxWithLidLargeThenSetBlockSmallOnTray-v1").spec
    lid, block = first_steps(spec)
    assert [c.type for c in lid.conditions + block.conditions] == ["fingertips_near", "grasped"]
    assert [c.object for c in lid.conditions + block.conditions] == ["box_with_lid", "block"]


def test_an_ordered_success_is_left_as_written():
    spec = version("GenDex/OpenDrawerChest2-v2").spec
    ordered = worked_by_hand(worked_by_hand(spec))
    assert ordered == worked_by_hand(spec)


@pytest.mark.parametrize("env_id", ["GenDex/PushBlockToGoal-v2", "GenDex/LiftApple-v3"])
def test_pushes_and_lifts_are_left_alone(env_id):
    """A push never holds its object; a lift already needs the grip at the end."""
    spec = version(env_id).spec
    assert worked_by_hand(spec) == spec


def test_the_rewrite_keeps_comments_and_anchors(tmp_path):
    source = version("GenDex/CloseCabinet-v3")
    text = source.files.spec.read_text()
    harder = worked_by_hand(source.spec)
    out = replace_success(text, harder)
    assert parse_task_spec(yaml.safe_load(out)) == harder
    before, _, _ = text.partition("\nsuccess:")
    assert out.startswith(before + "\nsuccess:")  # the header comments and the stages (with the &shut anchor) kept
    assert "max_episode_steps: 250" in out


def test_publishing_makes_the_next_version_and_refuses_twice(tmp_path):
    root = tmp_path / "tasks"
    shutil.copytree(version("GenDex/OpenBoxLid-v1").root, root / "OpenBoxLid" / "v1")
    (root / "OpenBoxLid" / "v1" / "solvability.json").write_text("{}")
    source = TaskVersion.at(root / "OpenBoxLid" / "v1")
    out = publish_worked_by_hand(source)
    assert out.env_id == "GenDex/OpenBoxLid-v2"
    assert load_task_spec(out.files.spec) == worked_by_hand(source.spec)
    assert not (out.root / "solvability.json").exists()  # measured again by the gate, not inherited
    record = json.loads((out.root / "revision.json").read_text())
    assert record["source"] == "GenDex/OpenBoxLid-v1" and "fingers" in record["changed"][0]
    assert out.files.spec.read_text().startswith(source.files.spec.read_text().split("\n")[0])
    with pytest.raises(NothingToHarden, match="already asks"):
        publish_worked_by_hand(out)
    assert sorted(p.name for p in (root / "OpenBoxLid").iterdir()) == ["v1", "v2"]


def test_every_committed_revision_is_its_source_worked_by_hand():
    """The versions published for the v2 suites' calibration are exactly the rule applied to their sources."""
    found = 0
    for record in sorted(TASKS.glob("*/v*/revision.json")):
        data = json.loads(record.read_text())
        if not any("success.sequence" in c for c in data["changed"]):
            continue
        found += 1
        here = TaskVersion.at(record.parent)
        assert here.spec == worked_by_hand(version(data["source"]).spec), here.env_id
    assert found >= 19
