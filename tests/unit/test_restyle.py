"""generator.restyle: the next version of a task without a scene, in a style dealt by the offline author's
rotation; only the scene changes, the solvability record is measured again."""

from __future__ import annotations

import json
import shutil
from collections import Counter

import pytest

from gendex_envs.registry import REPO_TASKS_DIR as TASKS
from gendex_envs.scene_spec import SceneSpec
from gendex_envs.spec import load_task_spec
from gendex_envs.task_version import TaskVersion
from generator.backends.offline_style import STYLE_ROTATION
from generator.restyle import RestyleError, add_scene, newest_without_scene, plan_restyle, publish_restyled


def _library(tmp_path, *folders: str) -> dict[str, TaskVersion]:
    root = tmp_path / "tasks"
    versions = {}
    for folder in folders:
        shutil.copytree(TASKS / folder, root / folder)
        v = TaskVersion.at(root / folder)
        versions[v.env_id] = v
    return versions


def test_add_scene_appends_the_style_and_keeps_every_other_byte():
    text = "# a comment\nname: X  # kept\ninstruction: grab it\n\n"
    out = add_scene(text, "lab")
    assert out.startswith(text.rstrip("\n")) and out.endswith("scene:\n  style: lab\n")
    with pytest.raises(RestyleError, match="already has a top-level 'scene'"):
        add_scene(out, "kitchen")


def test_publishing_makes_the_next_version_with_only_the_scene_changed(tmp_path):
    [source] = _library(tmp_path, "PutAppleBowl/v1").values()
    (source.root / "solvability.json").write_text("{}")
    out = publish_restyled(source, "workshop", {"rotation_seed": 0})
    assert out.env_id == "GenDex/PutAppleBowl-v2"
    spec = load_task_spec(out.files.spec)
    assert spec.scene == SceneSpec(style="workshop")
    assert spec == source.spec.__class__(**{**source.spec.__dict__, "scene": SceneSpec(style="workshop")})
    assert not (out.root / "solvability.json").exists()  # the structures touch physics: the gate measures again
    record = json.loads((out.root / "revision.json").read_text())
    assert record["source"] == "GenDex/PutAppleBowl-v1" and record["style"] == "workshop"
    assert (out.root / "reward.py").read_bytes() == (source.root / "reward.py").read_bytes()
    with pytest.raises(RestyleError, match="already has a scene"):
        publish_restyled(out, "lab")
    assert sorted(p.name for p in (source.root.parent).iterdir()) == ["v1", "v2"]


def test_the_plan_deals_the_rotation_over_the_newest_versions_without_a_scene(tmp_path):
    versions = _library(tmp_path, "PutAppleBowl/v0", "PutAppleBowl/v1", "LiftApple/v0", "PickUpBottle/v2",
                        "OpenDrawer/v2", "CloseDrawer/v3", "PushBlockToGoal/v2", "StackBlocks/v1")
    newest = newest_without_scene(versions.values())
    assert [v.env_id for v in newest] == sorted({f"GenDex/{n}" for n in (
        "CloseDrawer-v3", "LiftApple-v0", "OpenDrawer-v2", "PickUpBottle-v2", "PushBlockToGoal-v2", "PutAppleBowl-v1",
        "StackBlocks-v1")})
    plan = plan_restyle(versions)
    assert [p.source for p in plan] == newest
    # seven tasks in a row: every style of the rotation, none passed over in these layouts
    assert Counter(p.style for p in plan) == Counter(STYLE_ROTATION + STYLE_ROTATION[:1])
    # asking for some tasks does not change their styles
    some = plan_restyle(versions, names=["PutAppleBowl", "StackBlocks"])
    assert [(p.env_id, p.style) for p in some] == [(p.env_id, p.style) for p in plan
                                                     if p.source.name in ("PutAppleBowl", "StackBlocks")]
    published = publish_restyled(some[0].source, some[0].style)
    assert published.name not in {v.name for v in newest_without_scene([*versions.values(), published])}
    # the others keep their styles once one task has its scene (the rotation counts every task)
    after = plan_restyle({**versions, published.env_id: published})
    assert [(p.env_id, p.style) for p in after] == [(p.env_id, p.style) for p in plan
                                                      if p.source.name != published.name]


def test_the_command_names_a_task_that_already_has_a_scene(monkeypatch, tmp_path):
    from typer.testing import CliRunner

    from gendex.cli import app

    versions = _library(tmp_path, "PutAppleBowl/v1", "LiftApple/v0")
    published = publish_restyled(versions["GenDex/PutAppleBowl-v1"], "lab")
    monkeypatch.setattr("gendex_envs.registry.registered_tasks",
                        lambda: {**versions, published.env_id: published})
    result = CliRunner().invoke(app, ["restyle", "PutAppleBowl", "LiftApple", "--dry-run"])
    assert result.exit_code == 0, result.output
    assert "PutAppleBowl: its newest version already has a scene" in result.output
    assert "GenDex/LiftApple-v0: " in result.output and "1 tasks to restyle (dry run)" in result.output
    unknown = CliRunner().invoke(app, ["restyle", "NoSuchTask"])
    assert unknown.exit_code == 2 and "no registered task named NoSuchTask" in unknown.output
