"""Unit tests of the task YAML schema (gendex_envs.spec): loading, error messages, round trip."""

from __future__ import annotations

import copy
import dataclasses
import re
from pathlib import Path

import pytest
import yaml

from gendex_envs.errors import TaskSpecError
from gendex_envs.spec import (
    CONDITION_TYPES,
    CONTROL_JOINT_MODES,
    KEYFRAMES,
    ROBOT_UIDS,
    SKILLS,
    STAGE_METHODS,
    ConditionSpec,
    ObjectSpec,
    TaskSpec,
    dump_task_spec,
    load_task_spec,
    parse_task_spec,
    spec_to_dict,
)
from gendex_envs.task_version import TaskLayout

PUT_APPLE_BOWL = """\
name: PutAppleBowl
instruction: Pick up the apple and put it into the bowl.
table:
  size_m: [1.6, 1.2]
  height_m: 0.76
robot:
  init_keyframe: pregrasp_open
objects:
  - name: apple
    asset: ycb_013_apple
    pos_m: [0.05, -0.10, 0.0]
    randomize: {xy_m: [0.03, 0.03], yaw_deg: 180}
  - name: bowl
    asset: ycb_024_bowl
    scale: 1.2
    pos_m: [0.10, 0.15, 0.0]
    color_rgba: [0.9, 0.9, 0.9, 1.0]
stages:
  - name: reach
    instruction: Move the open hand above the apple.
    skill: reach
    method: motion_planning
    control_joint: arm
    horizon: 60
    target: apple
  - name: grasp
    instruction: Close the fingers around the apple.
    skill: grasp
    method: RL
    control_joint: hand
    target: apple
  - name: move
    instruction: Carry the apple above the bowl.
    skill: carry
    method: motion_planning
    control_joint: arm
    target: bowl
  - name: release
    instruction: Open the hand to drop the apple into the bowl.
    skill: release
    method: RL
    control_joint: hand
    horizon: 40
success:
  description: The apple rests inside the bowl.
  conditions:
    - {type: inside, object: apple, target: bowl}
  hold_steps: 10
max_episode_steps: 300
"""

ASSETS = {"ycb_013_apple", "ycb_024_bowl", "ycb_003_cracker_box", "partnet_cabinet_1000"}


@pytest.fixture
def raw() -> dict:
    return yaml.safe_load(PUT_APPLE_BOWL)


def write(tmp_path: Path, data: dict | str) -> Path:
    path = TaskLayout(tmp_path).spec
    path.write_text(data if isinstance(data, str) else yaml.safe_dump(data, sort_keys=False))
    return path


def load_bad(tmp_path: Path, data: dict | str, **kw) -> str:
    path = write(tmp_path, data)
    with pytest.raises(TaskSpecError) as info:
        load_task_spec(path, **kw)
    msg = str(info.value)
    assert str(path) in msg, msg
    return msg


# ------------------------------------------------------------------------------------- valid files
def test_example_loads_with_defaults(tmp_path: Path) -> None:
    spec = load_task_spec(write(tmp_path, PUT_APPLE_BOWL), known_assets=ASSETS)
    assert isinstance(spec, TaskSpec)
    assert spec.name == "PutAppleBowl"
    assert [o.name for o in spec.objects] == ["apple", "bowl"]
    apple = spec.object("apple")
    assert apple.scale == 1.0 and isinstance(apple.scale, float)
    assert apple.pos_m == (0.05, -0.10, 0.0)
    assert apple.quat_wxyz == (1.0, 0.0, 0.0, 0.0)
    assert apple.randomize.yaw_deg == 180.0 and isinstance(apple.randomize.yaw_deg, float)
    assert apple.joint_state == {} and apple.fixed is False and apple.color_rgba is None
    assert spec.object("bowl").color_rgba == (0.9, 0.9, 0.9, 1.0)
    assert spec.table.friction == 0.8
    assert spec.robot.uid == "ur10e_shadow" and spec.robot.init_keyframe == "pregrasp_open"
    assert spec.robot.base_pos_m == (-0.8, 0.0, 0.0)
    assert spec.goal is None
    assert [s.horizon for s in spec.stages] == [60, 100, 100, 40]
    assert spec.stages[3].target is None
    assert spec.success.conditions == (ConditionSpec(type="inside", object="apple", target="bowl"),)
    assert spec.max_episode_steps == 300


def test_spec_is_frozen(raw: dict) -> None:
    spec = parse_task_spec(raw)
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.name = "Other"  # type: ignore[misc]
    assert isinstance(spec.objects, tuple) and isinstance(spec.stages, tuple)


def test_round_trip_dump_parse(raw: dict) -> None:
    raw["goal"] = {"pos_m": [0.1, 0.15, 0.1]}
    raw["objects"][0]["joint_state"] = {"lid": 0.25}
    raw["objects"][1]["fixed"] = True
    raw["success"]["conditions"].append({"type": "near", "object": "apple", "target": "goal", "max_dist_m": 0.08})
    raw["success"]["conditions"].append({"type": "lifted", "object": "apple", "min_height_m": 0.05})
    spec = parse_task_spec(raw)
    text = dump_task_spec(spec)
    assert "null" not in text  # None-valued optional fields are omitted
    assert parse_task_spec(yaml.safe_load(text)) == spec
    d = spec_to_dict(spec)
    assert d["objects"][0]["pos_m"] == [0.05, -0.10, 0.0] and isinstance(d["objects"][0]["pos_m"], list)
    assert d["goal"] == {"pos_m": [0.1, 0.15, 0.1], "radius_m": 0.05}
    assert parse_task_spec(d) == spec


def test_load_file_round_trip(tmp_path: Path, raw: dict) -> None:
    spec = parse_task_spec(raw)
    path = TaskLayout(tmp_path).spec
    path.write_text(dump_task_spec(spec))
    assert load_task_spec(path) == spec


def test_allowed_value_constants() -> None:
    assert CONTROL_JOINT_MODES == ("arm", "hand", "both", "three_finger", "arm_two_finger", "lift_inspire")
    assert STAGE_METHODS == ("motion_planning", "RL")
    assert CONDITION_TYPES == ("lifted", "inside", "near", "joint_open", "rotated", "grasped", "released", "over",
                               "hand_at", "fingertips_near", "hand_open", "placed", "joint_at", "upright", "flipped",
                               "at_rest", "wiped", "hung", "poured")
    assert SKILLS == ("reach", "grasp", "lift", "carry", "place", "release", "open", "close", "push", "turn",
                      "reorient", "press", "twist", "wipe", "hang", "pour", "flip")
    assert KEYFRAMES == ("rest", "pregrasp_open", "palm_up")
    assert ROBOT_UIDS == ("ur10e_shadow",)


def test_object_lookup_unknown_name_suggests(raw: dict) -> None:
    spec = parse_task_spec(raw)
    assert isinstance(spec.object("bowl"), ObjectSpec)
    with pytest.raises(TaskSpecError, match=r"'aple'.*Did you mean: 'apple'"):
        spec.object("aple")


# ----------------------------------------------------------------------------------- unknown keys
def test_unknown_top_level_key_suggests(tmp_path: Path, raw: dict) -> None:
    raw["objcts"] = raw.pop("objects")
    msg = load_bad(tmp_path, raw)
    assert "'objcts'" in msg and "Did you mean: 'objects'" in msg
    assert "Allowed keys:" in msg


def test_unknown_key_inside_object_names_index(tmp_path: Path, raw: dict) -> None:
    raw["objects"][1]["scael"] = 1.0
    msg = load_bad(tmp_path, raw)
    assert "objects[1]" in msg and "'scael'" in msg and "Did you mean: 'scale'" in msg


def test_unknown_key_in_nested_dataclass(raw: dict) -> None:
    raw["objects"][0]["randomize"]["yaw"] = 10
    with pytest.raises(TaskSpecError, match=r"objects\[0\]\.randomize: unknown key 'yaw'.*'yaw_deg'"):
        parse_task_spec(raw, source="t.yaml")


def test_unknown_key_in_condition(raw: dict) -> None:
    raw["success"]["conditions"][0]["obj"] = "apple"
    with pytest.raises(TaskSpecError, match=r"success\.conditions\[0\]: unknown key 'obj'.*'object'"):
        parse_task_spec(raw)


# -------------------------------------------------------------------------------------- enum values
def test_bad_control_joint_lists_modes_and_suggests(tmp_path: Path, raw: dict) -> None:
    raw["stages"][0]["control_joint"] = "arms"
    msg = load_bad(tmp_path, raw)
    assert "stages[0].control_joint" in msg and "'arms'" in msg
    for mode in CONTROL_JOINT_MODES:
        assert repr(mode) in msg
    assert "Did you mean: 'arm'" in msg


def test_bad_method_and_keyframe(raw: dict) -> None:
    bad = copy.deepcopy(raw)
    bad["stages"][2]["method"] = "rl"
    with pytest.raises(TaskSpecError, match=r"stages\[2\]\.method = 'rl'.*'motion_planning', 'RL'.*Did you mean: 'RL'"):
        parse_task_spec(bad)
    raw["robot"]["init_keyframe"] = "pregrasp"
    with pytest.raises(TaskSpecError, match=r"robot\.init_keyframe = 'pregrasp'.*Did you mean: 'pregrasp_open'"):
        parse_task_spec(raw)


def test_bad_condition_type(raw: dict) -> None:
    raw["success"]["conditions"][0]["type"] = "insde"
    with pytest.raises(TaskSpecError, match=r"success\.conditions\[0\]\.type = 'insde'.*Did you mean: 'inside'"):
        parse_task_spec(raw)


# ----------------------------------------------------------------------------------- ranges, values
def test_scale_out_of_range(tmp_path: Path, raw: dict) -> None:
    raw["objects"][0]["scale"] = 5.0
    msg = load_bad(tmp_path, raw)
    assert "objects[0].scale" in msg and "5.0" in msg and "0.3 <= scale <= 2.0" in msg


def test_quaternion_not_unit(raw: dict) -> None:
    raw["objects"][1]["quat_wxyz"] = [1.0, 0.1, 0.0, 0.0]
    with pytest.raises(TaskSpecError, match=r"objects\[1\]\.quat_wxyz = \[1\.0, 0\.1, 0\.0, 0\.0\].*unit quaternion"):
        parse_task_spec(raw)
    raw["objects"][1]["quat_wxyz"] = [0.7071, 0.0, 0.0, 0.7071]  # unit within 1e-3: accepted as is
    assert parse_task_spec(raw).objects[1].quat_wxyz == (0.7071, 0.0, 0.0, 0.7071)


def test_several_semantic_problems_reported_together(raw: dict) -> None:
    raw["name"] = "put_apple_bowl"
    raw["objects"][0]["color_rgba"] = [2.0, 0.0, 0.0, 1.0]
    raw["objects"][1]["randomize"] = {"yaw_deg": -5}
    raw["stages"][1]["horizon"] = 0
    with pytest.raises(TaskSpecError) as info:
        parse_task_spec(raw, source="x.yaml")
    msg = str(info.value)
    assert "4 problems" in msg
    for part in ("name = 'put_apple_bowl'", "CamelCase", "objects[0].color_rgba", "[0, 1]",
                 "objects[1].randomize.yaw_deg = -5.0", "stages[1].horizon = 0"):
        assert part in msg


def test_non_finite_and_negative_clearance(raw: dict) -> None:
    raw["objects"][0]["pos_m"] = [0.0, float("nan"), -0.1]
    with pytest.raises(TaskSpecError) as info:
        parse_task_spec(raw)
    msg = str(info.value)
    assert "objects[0].pos_m[1] = nan" in msg and "finite" in msg
    assert "objects[0].pos_m" in msg and ">= 0" in msg


def test_name_patterns_and_empty_instruction(raw: dict) -> None:
    raw["objects"][0]["name"] = "Apple"
    raw["instruction"] = "  "
    with pytest.raises(TaskSpecError, match=r"instruction = '  '[\s\S]*objects\[0\]\.name = 'Apple'"):
        parse_task_spec(raw)


# ---------------------------------------------------------------------------------- assets, references
def test_unknown_asset_suggests_close_id(tmp_path: Path, raw: dict) -> None:
    raw["objects"][1]["asset"] = "ycb_024_bowel"
    msg = load_bad(tmp_path, raw, known_assets=ASSETS)
    assert "objects[1].asset" in msg and "'ycb_024_bowel'" in msg
    assert "Did you mean: 'ycb_024_bowl'" in msg and "gendex assets" in msg
    assert load_task_spec(write(tmp_path, raw)).objects[1].asset == "ycb_024_bowel"  # unchecked without catalog


def test_duplicate_object_names(raw: dict) -> None:
    raw["objects"][1]["name"] = "apple"
    with pytest.raises(TaskSpecError, match=r"objects\[1\]\.name = 'apple'.*unique"):
        parse_task_spec(raw)


def test_condition_references_unknown_object(raw: dict) -> None:
    raw["success"]["conditions"][0]["target"] = "bowll"
    with pytest.raises(TaskSpecError, match=r"success\.conditions\[0\]\.target = 'bowll'.*Did you mean: 'bowl'"):
        parse_task_spec(raw)
    raw["success"]["conditions"][0] = {"type": "lifted", "object": "banana", "min_height_m": 0.1}
    with pytest.raises(TaskSpecError, match=r"success\.conditions\[0\]\.object = 'banana' does not name an object"):
        parse_task_spec(raw)


def test_stage_target_unknown(raw: dict) -> None:
    raw["stages"][0]["target"] = "appel"
    with pytest.raises(TaskSpecError, match=r"stages\[0\]\.target = 'appel'.*Did you mean: 'apple'"):
        parse_task_spec(raw)


def test_near_goal_requires_goal_and_distance(raw: dict) -> None:
    raw["success"]["conditions"] = [{"type": "near", "object": "apple", "target": "goal"}]
    with pytest.raises(TaskSpecError) as info:
        parse_task_spec(raw)
    msg = str(info.value)
    assert "success.conditions[0].target = 'goal'" in msg and "needs a top-level `goal:`" in msg
    assert "success.conditions[0].max_dist_m is required for type 'near'" in msg
    raw["goal"] = {"pos_m": [0.2, 0.0, 0.15], "radius_m": 0.04}
    raw["success"]["conditions"][0]["max_dist_m"] = 0.05
    assert parse_task_spec(raw).success.conditions[0].target == "goal"


def test_required_fields_per_condition_type(raw: dict) -> None:
    for cond, field in [({"type": "lifted", "object": "apple"}, "min_height_m"),
                        ({"type": "inside", "object": "apple"}, "target"),
                        ({"type": "joint_open", "object": "bowl"}, "min_fraction")]:
        raw["success"]["conditions"] = [cond]
        with pytest.raises(TaskSpecError, match=rf"conditions\[0\]\.{field} is required for type '{cond['type']}'"):
            parse_task_spec(raw)
    raw["success"]["conditions"] = [{"type": "joint_open", "object": "bowl", "min_fraction": 1.5}]
    with pytest.raises(TaskSpecError, match=r"min_fraction = 1\.5 is not allowed.*\(0, 1\]"):
        parse_task_spec(raw)


# ------------------------------------------------------------------------------- types, structure
def test_missing_required_field_named(tmp_path: Path, raw: dict) -> None:
    del raw["objects"][1]["pos_m"]
    msg = load_bad(tmp_path, raw)
    assert "objects[1].pos_m" in msg and "missing" in msg and "list of 3 numbers" in msg
    raw["objects"][1]["pos_m"] = [0.1, 0.1, 0.0]
    del raw["success"]
    with pytest.raises(TaskSpecError, match=r"success: required field is missing"):
        parse_task_spec(raw)


def test_wrong_type_names_field_and_type(tmp_path: Path, raw: dict) -> None:
    raw["objects"][0]["scale"] = "big"
    msg = load_bad(tmp_path, raw)
    assert "objects[0].scale = 'big'" in msg and "str" in msg and "expected a number" in msg


@pytest.mark.parametrize(("where", "value", "pattern"), [
    (("stages", 0, "horizon"), 1.5, r"stages\[0\]\.horizon = 1\.5.*expected an integer"),
    (("stages", 0, "horizon"), True, r"stages\[0\]\.horizon = True.*expected an integer"),
    (("objects", 0, "fixed"), "yes please", r"objects\[0\]\.fixed = 'yes please'.*boolean"),
    (("objects", 0, "pos_m"), [0.1, 0.2], r"objects\[0\]\.pos_m = \[0\.1, 0\.2\].*list of 3 numbers"),
    (("objects", 0, "joint_state"), {"lid": "open"}, r"objects\[0\]\.joint_state.*mapping from a string to a number"),
    (("success", "conditions"), "apple inside bowl", r"success\.conditions = 'apple inside bowl'.*list of"),
])
def test_wrong_types(raw: dict, where: tuple, value: object, pattern: str) -> None:
    node = raw
    for key in where[:-1]:
        node = node[key]
    node[where[-1]] = value
    with pytest.raises(TaskSpecError, match=pattern):
        parse_task_spec(raw)


def test_objects_not_a_mapping(raw: dict) -> None:
    raw["objects"][1] = "bowl"
    with pytest.raises(TaskSpecError, match=r"objects\[1\]: expected a mapping"):
        parse_task_spec(raw)
    with pytest.raises(TaskSpecError, match=r"top level: expected a mapping"):
        parse_task_spec(["not", "a", "mapping"])  # type: ignore[arg-type]


def test_empty_objects_and_stages(raw: dict) -> None:
    raw["objects"], raw["stages"] = [], []
    with pytest.raises(TaskSpecError, match=r"objects = \[\].*at least one object[\s\S]*stages = \[\]"):
        parse_task_spec(raw)


def test_yaml_syntax_error_names_file_and_line(tmp_path: Path) -> None:
    text = PUT_APPLE_BOWL.replace("    scale: 1.2\n", "    scale: [1.2\n")
    msg = load_bad(tmp_path, text)
    assert "invalid YAML" in msg and re.search(r"line \d+", msg), msg


def test_duplicate_yaml_key_rejected(tmp_path: Path) -> None:
    text = PUT_APPLE_BOWL.replace("max_episode_steps: 300\n", "max_episode_steps: 300\nname: Again\n")
    line = text.splitlines().index("name: Again") + 1
    msg = load_bad(tmp_path, text)
    assert "duplicate key 'name'" in msg and f"line {line}," in msg


def test_empty_and_missing_file(tmp_path: Path) -> None:
    assert "empty" in load_bad(tmp_path, "")
    with pytest.raises(TaskSpecError, match="cannot read task spec .*nope.yaml"):
        load_task_spec(tmp_path / "nope.yaml")


def test_docs_example_is_valid(repo_root: Path) -> None:
    """The full example under "## Example" parses; so does every smaller snippet's success section."""
    doc = (repo_root / "docs" / "task_spec.md").read_text()
    block = re.search(r"## Example\n.*?```yaml\n(.*?)```", doc, re.S)
    assert block is not None
    full = yaml.safe_load(block.group(1))
    spec = parse_task_spec(full, source="docs/task_spec.md")
    assert spec.name == "PutAppleBowl" and spec.goal is not None and len(spec.stages) == 4
    snippets = [yaml.safe_load(b) for b in re.findall(r"```yaml\n(.*?)```", doc, re.S)]
    for snippet in snippets:
        if "success" in snippet and "name" not in snippet:  # a success section: in the example's place
            objects = [{"name": n, "asset": "ycb_013_apple", "pos_m": [0.1, 0.0, 0.0]} for n in ("drawer",)]
            parse_task_spec({**full, "objects": [*full["objects"], *objects], "success": snippet["success"]},
                            source="docs/task_spec.md snippet")
    assert len(snippets) >= 2


# --------------------------------------------------------------------- skills and declared success
def test_skill_is_required_and_checked(raw: dict) -> None:
    del raw["stages"][0]["skill"]
    with pytest.raises(TaskSpecError, match=r"stages\[0\]\.skill: required field is missing.*'reach', 'grasp'"):
        parse_task_spec(raw)
    raw["stages"][0]["skill"] = "approach"
    with pytest.raises(TaskSpecError, match=r"stages\[0\]\.skill = 'approach' is not allowed; allowed values: 'reach'"):
        parse_task_spec(raw)


def test_stage_success_conditions_parse_and_default_to_the_task(raw: dict) -> None:
    raw["stages"][1]["success"] = [{"type": "grasped", "object": "apple", "min_fingers": 3, "max_palm_force_n": 10},
                                   {"type": "hand_open", "min_spread_m": 0.1, "negate": True}]
    spec = parse_task_spec(raw)
    grasp = spec.stages[1]
    assert grasp.success[0] == ConditionSpec(type="grasped", object="apple", min_fingers=3, max_palm_force_n=10.0)
    assert grasp.success[1].negate is True and grasp.success[1].object is None
    assert spec.stage_conditions(grasp) == grasp.success
    assert spec.stages[0].success is None and spec.stage_conditions(spec.stages[0]) == spec.success.conditions
    text = dump_task_spec(spec)
    assert "negate: false" not in text and "negate: true" in text
    assert parse_task_spec(yaml.safe_load(text)) == spec


@pytest.mark.parametrize(("cond", "pattern"), [
    ({"type": "lifted", "object": "apple", "min_height_m": 0.1, "min_fraction": 0.5},
     r"min_fraction = 0\.5 does not apply to type 'lifted' \(the object has risen.*its fields: object, min_height_m"),
    ({"type": "over", "object": "apple", "target": "bowl", "max_xy_m": 0.05, "min_dz_m": 0.1},
     r"max_dz_m is required for type 'over'"),
    ({"type": "over", "object": "apple", "target": "bowl", "max_xy_m": 0.05, "min_dz_m": 0.2, "max_dz_m": 0.1},
     r"max_dz_m = 0\.1 is not allowed; must be > min_dz_m \(0\.2\)"),
    ({"type": "grasped", "object": "apple", "min_fingers": 5}, r"min_fingers = 5 is not allowed; must be between 1"),
    ({"type": "rotated", "object": "apple", "min_deg": 0}, r"min_deg = 0\.0 is not allowed; must be non-zero"),
    ({"type": "hand_at", "object": "apple", "max_dist_m": -0.1}, r"max_dist_m = -0\.1 is not allowed; must be > 0"),
    ({"type": "hand_open"}, r"min_spread_m is required for type 'hand_open'"),
    ({"type": "grasped", "object": "apple", "part": "lid"}, r"part = 'lid' is not allowed; allowed values: 'handle'"),
    ({"type": "released", "object": "pear"}, r"object = 'pear' does not name an object"),
])
def test_stage_condition_fields_are_checked_per_type(raw: dict, cond: dict, pattern: str) -> None:
    raw["stages"][3]["success"] = [cond]
    with pytest.raises(TaskSpecError, match=r"stages\[3\]\.success\[0\]\." + pattern):
        parse_task_spec(raw)


def test_empty_stage_success_is_refused(raw: dict) -> None:
    raw["stages"][0]["success"] = []
    with pytest.raises(TaskSpecError, match=r"stages\[0\]\.success = \[\] is not allowed; leave it out"):
        parse_task_spec(raw)
