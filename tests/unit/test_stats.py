"""`gendex stats`: tasks per skill, assets, stages, articulated vs rigid, instruction and scene diversity."""

import json

import pytest
from typer.testing import CliRunner

from gendex.cli import app
from generator.phrasing import split
from generator.stats import TASK_SKILLS, instruction_diversity, jaccard, library_stats, task_skills

EXPECTED = {
    "PutAppleBowl": ("put_in",), "PickUpBottle": ("lift",), "OpenCabinet": ("open_door",),
    "CloseCabinet": ("close_door",), "CloseMicrowave": ("close_door",), "OpenDrawer": ("open_drawer",),
    "CloseDrawer": ("close_drawer",), "OpenTrashCan": ("open_lid",), "OpenBoxLid": ("open_lid",),
    "CloseTrashCan": ("close_lid",), "TurnFaucet": ("turn",), "StackBlocks": ("stack",),
    "PushBlockToGoal": ("push",), "SetBottleOnPlate": ("place_on",), "RotateTennisBall": ("reorient",),
    "PressButtonEstop": ("press",), "HandOverBottle": ("hand_over",), "UnscrewJar": ("twist",),
}


def test_each_reference_task_is_counted_under_its_skill(committed_tasks):
    latest = {}
    for v in committed_tasks.values():
        if v.name in EXPECTED and v.version >= latest.get(v.name, (-1, None))[0]:
            latest[v.name] = (v.version, v)
    assert set(latest) == set(EXPECTED)
    for name, (_, v) in latest.items():
        assert task_skills(v.spec) == EXPECTED[name], name


def test_library_numbers_add_up(committed_tasks):
    tasks = committed_tasks
    s = library_stats(tasks, diversity=False)
    names = {v.name for v in tasks.values()}
    assert s["tasks"] == len(names) and s["versions"] == "latest"
    assert s["skills_covered"] == len(TASK_SKILLS) == 23  # a task for every skill
    assert sum(s["stages_per_task"]["histogram"].values()) == s["tasks"]
    assert s["articulated_tasks"] + s["rigid_tasks"] == s["tasks"]
    assert s["assets_used"] == len(s["assets"]) and "apple" in s["assets"]
    assert library_stats(tasks, all_versions=True, diversity=False)["tasks"] == len(tasks) > s["tasks"]
    assert 0.0 < s["scene_diversity"]["mean_pairwise_category_jaccard"] < 0.5
    assert 0.5 < s["scene_diversity"]["skill_entropy"] <= 1.0


def test_instruction_diversity_is_the_mean_pairwise_minilm_cosine():
    same, source = instruction_diversity(["Open the drawer."] * 3)
    assert same == pytest.approx(1.0, abs=1e-4) and "all-MiniLM-L6-v2" in source
    near, _ = instruction_diversity(["Put the apple into the bowl.", "Put the lemon into the bowl."])
    far, _ = instruction_diversity(["Put the apple into the bowl.", "Turn the faucet lever to the side."])
    assert 1.0 > near > far > -1.0
    assert instruction_diversity(["one"]) == (None, "fewer than two tasks")
    assert jaccard({"apple", "bowl"}, {"apple"}) == 0.5


def test_cli_stats_json():
    r = CliRunner().invoke(app, ["stats", "--json", "--no-diversity"])
    assert r.exit_code == 0, r.output
    s = json.loads(r.output[r.output.index("{"):])
    assert s["skills_covered"] == 23 and s["instruction_diversity"]["published"]["GenDexHand"] == 0.288


def test_the_commands_alone_are_measured_beside_the_framed_instructions(task_version):
    """The framing (situation, purpose) lowers the figure; the stats show how much by measuring the commands
    alone: for a framed library the commands read more alike than the instructions."""
    names = ("LiftLemon", "PutPlumInPot", "CloseCabinet", "OpenMicrowaveStandard", "SetRacquetballOnPlate")
    versions = {task_version(n).env_id: task_version(n) for n in names}
    s = library_stats(versions)["instruction_diversity"]
    assert s["commands_only"] is not None and s["commands_only"] > s["mean_pairwise_cosine"]
    bare = [split(v.spec.instruction)[1] for v in versions.values()]
    assert s["commands_only"] == pytest.approx(instruction_diversity(bare)[0])
    assert all(b and b[0].islower() for b in bare)
    assert library_stats(versions, diversity=False)["instruction_diversity"]["commands_only"] is None
