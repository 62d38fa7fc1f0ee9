"""Unit tests of the critic's directive grammar (generator.critic.directives): parsing and arithmetic."""

from __future__ import annotations

import math

import pytest

from gendex_envs.errors import TaskSpecError
from gendex_envs.spec import SCALE_RANGE, TaskSpec, spec_to_dict
from generator.critic.directives import (
    Directive,
    apply_directives,
    axis_quat,
    parse_directives,
)
from generator.errors import DirectiveError, ModelOutputError

NAMES = ("apple", "bowl", "red_block")


@pytest.fixture(scope="module")
def spec(task_version) -> TaskSpec:
    return task_version("PutAppleBowl", 0).spec


# ------------------------------------------------------------------------------------------------ parsing
@pytest.mark.parametrize(("line", "expected"), [
    ("Scale_Action: apple - 0.5", Directive("scale", "apple", "scale", 0.5)),
    ("Scale_Action: bowl - 2", Directive("scale", "bowl", "scale", 2.0)),
    ("Position_Action: apple - move_x 0.05", Directive("position", "apple", "move_x", 0.05)),
    ("Position_Action: apple - move_y -0.1", Directive("position", "apple", "move_y", -0.1)),
    ("Position_Action: red_block - move_z .02", Directive("position", "red_block", "move_z", 0.02)),
    ("Pose_Action: bowl - rotate_x 90", Directive("pose", "bowl", "rotate_x", 90.0)),
    ("Pose_Action: bowl - rotate_y -45.5", Directive("pose", "bowl", "rotate_y", -45.5)),
    ("Pose_Action: apple - rotate_z 1e1", Directive("pose", "apple", "rotate_z", 10.0)),
])
def test_every_form_parses(line, expected):
    (d,) = parse_directives(line, NAMES)
    assert d == expected
    assert d.line == line


@pytest.mark.parametrize("line", [
    "  scale_action:   apple -   0.5  ",
    "- Scale_Action: apple - 0.5",
    "* `Scale_Action: apple - 0.5`",
    "`Scale_Action: apple - 0.5`",
    "1. SCALE_ACTION: Apple - 0.5",
    "**Scale_Action:** apple - 0.5",
    "Scale Action: apple \u2013 0.5",
    "Scale_Action: apple - 0.5x  # too big",
    "Scale_Action: apple - 0.5.",
    "Scale_Action apple - 0.5",
])
def test_layout_is_tolerated(line):
    assert parse_directives(line, NAMES) == [Directive.scale("apple", 0.5)]


def test_units_and_case_of_operations():
    text = ("Position_Action: apple - MOVE_X 0.05 m\nPose_Action: apple - Rotate_Z 90 deg\n"
            "Pose_Action: apple - rotate_z 90\u00b0")
    assert parse_directives(text, NAMES) == [Directive.move("apple", "x", 0.05), Directive.rotate("apple", "z", 90),
                                             Directive.rotate("apple", "z", 90)]


def test_prose_is_ignored_and_order_is_kept():
    text = """The apple is too large and floats above the table.
I suggest these edits (Scale_Action halves it):
- Scale_Action: apple - 0.5

Position_Action: apple - move_z -0.3
Scale_Action: none
Pose action is not needed.
Everything else looks fine."""
    assert parse_directives(text, NAMES) == [Directive.scale("apple", 0.5), Directive.move("apple", "z", -0.3)]
    assert parse_directives("no directives here", NAMES) == []
    assert parse_directives("", NAMES) == []


@pytest.mark.parametrize(("line", "needle"), [
    ("Scale_Action: apple 0.5", "Scale_Action: <object> - <factor>"),
    ("Scale_Action: apple - big", "Scale_Action: <object> - <factor>"),
    ("Scale_Action:", "nothing after the keyword"),
    ("Scale_Action: apple - 0", "must be > 0"),
    ("Scale_Action: apple - -0.5", "must be > 0"),
    ("Position_Action: apple - move_w 0.1", "'move_w'"),
    ("Position_Action: apple - move_x", "Position_Action: <object> - move_x|move_y|move_z <metres>"),
    ("Position_Action: apple - rotate_x 0.1", "'rotate_x'"),
    ("Pose_Action: apple - rotate_z ninety", "Pose_Action: <object> - rotate_x|rotate_y|rotate_z <degrees>"),
    ("Pose_Action: apple - spin_z 90", "'spin_z'"),
])
def test_malformed_directives_raise_naming_the_line_and_forms(line, needle):
    with pytest.raises(DirectiveError) as e:
        parse_directives(f"Looks fine.\n{line}\n", NAMES)
    msg = str(e.value)
    assert needle in msg
    assert repr(line) in msg and "Allowed forms" in msg


def test_malformed_error_lists_all_forms():
    with pytest.raises(DirectiveError) as e:
        parse_directives("Position_Action: apple move_x 0.1", NAMES)
    msg = str(e.value)
    assert "'Position_Action: apple move_x 0.1'" in msg
    for form in ("Scale_Action: <object> - <factor>", "move_x|move_y|move_z", "rotate_x|rotate_y|rotate_z"):
        assert form in msg


def test_unknown_object_names_it_lists_objects_and_suggests():
    with pytest.raises(DirectiveError) as e:
        parse_directives("Scale_Action: aple - 0.5", NAMES)
    msg = str(e.value)
    assert "'aple'" in msg and "apple, bowl, red_block" in msg and "Did you mean: 'apple'" in msg
    with pytest.raises(DirectiveError, match="'banana'"):
        parse_directives("Position_Action: banana - move_x 0.1", NAMES)
    with pytest.raises(DirectiveError, match="Did you mean: 'red_block'"):
        parse_directives("Pose_Action: red-block - rotate_z 90", NAMES)


def test_directive_error_is_a_model_output_error():
    assert issubclass(DirectiveError, ModelOutputError) and issubclass(DirectiveError, ValueError)


def test_canonical_text_round_trips():
    ds = [Directive.scale("apple", 0.5), Directive.move("bowl", "y", -0.125), Directive.rotate("apple", "x", 90),
          Directive.move("apple", "z", 1e-05), Directive.scale("bowl", 1 / 3)]
    assert [str(d) for d in ds[:3]] == ["Scale_Action: apple - 0.5", "Position_Action: bowl - move_y -0.125",
                                        "Pose_Action: apple - rotate_x 90.0"]
    assert parse_directives("\n".join(map(str, ds)), NAMES) == ds


def test_directive_validates_itself():
    with pytest.raises(DirectiveError, match="must be > 0"):
        Directive.scale("apple", 0.0)
    with pytest.raises(DirectiveError, match="no operation 'move_x'"):
        Directive("pose", "apple", "move_x", 1.0)
    with pytest.raises(DirectiveError, match="not finite"):
        Directive.move("apple", "x", math.inf)
    with pytest.raises(DirectiveError, match="unknown directive kind"):
        Directive("color", "apple", "scale", 1.0)


# --------------------------------------------------------------------------------------------- arithmetic
def test_move_adds_exactly(spec):
    out = apply_directives(spec, [Directive.move("apple", "x", 0.05), Directive.move("apple", "y", -0.02),
                                  Directive.move("apple", "z", 0.01)])
    x, y, z = spec.object("apple").pos_m
    assert out.object("apple").pos_m == (x + 0.05, y - 0.02, z + 0.01)
    assert out.object("bowl") == spec.object("bowl")
    assert spec.object("apple").pos_m == (x, y, z)  # the input is untouched


def test_move_z_clamps_the_clearance_at_zero(spec):
    up = apply_directives(spec, [Directive.move("apple", "z", 0.3)])
    assert up.object("apple").pos_m[2] == pytest.approx(0.3)
    down = apply_directives(up, [Directive.move("apple", "z", -0.5)])
    assert down.object("apple").pos_m[2] == 0.0


def test_scale_is_a_factor(spec):
    half = apply_directives(spec, parse_directives("Scale_Action: bowl - 0.5", ["apple", "bowl"]))
    assert half.object("bowl").scale == 0.5
    again = apply_directives(half, [Directive.scale("bowl", 3.0)])
    assert again.object("bowl").scale == pytest.approx(1.5)
    assert again.object("bowl").pos_m == spec.object("bowl").pos_m  # scaling keeps the position and clearance


def test_scale_outside_range_is_rejected_not_clamped(spec):
    lo, hi = SCALE_RANGE
    with pytest.raises(DirectiveError) as e:
        apply_directives(spec, [Directive.scale("apple", 2.5)])
    msg = str(e.value)
    assert "'apple'" in msg and "2.5" in msg and f"{lo} <= scale <= {hi}" in msg and "factors allowed" in msg
    with pytest.raises(DirectiveError, match="0.2"):
        apply_directives(spec, [Directive.scale("apple", 0.2)])
    assert apply_directives(spec, [Directive.scale("apple", 2.0)]).object("apple").scale == hi  # bounds included


def test_rotations_compose_in_the_world_frame(spec):
    twice = apply_directives(spec, [Directive.rotate("apple", "z", 90)] * 2)
    once = apply_directives(spec, [Directive.rotate("apple", "z", 180)])
    assert twice.object("apple").quat_wxyz == pytest.approx(once.object("apple").quat_wxyz, abs=1e-12)
    assert once.object("apple").quat_wxyz == pytest.approx((0.0, 0.0, 0.0, 1.0), abs=1e-12)
    full = apply_directives(spec, [Directive.rotate("apple", "x", 360)])
    assert full.object("apple").quat_wxyz == pytest.approx((1.0, 0.0, 0.0, 0.0), abs=1e-12)
    # world frame: x then z is q_z * q_x (the later rotation on the left)
    xz = apply_directives(spec, [Directive.rotate("bowl", "x", 90), Directive.rotate("bowl", "z", 90)])
    c = math.sqrt(0.5)
    assert xz.object("bowl").quat_wxyz == pytest.approx((0.5, 0.5, 0.5, 0.5), abs=1e-12)
    assert axis_quat("z", 90) == pytest.approx((c, 0.0, 0.0, c))


def test_rotation_keeps_unit_norm(spec):
    ds = [Directive.rotate("apple", axis, deg) for axis, deg in zip("xyzxyz" * 20, range(7, 847, 7), strict=True)]
    q = apply_directives(spec, ds).object("apple").quat_wxyz
    assert math.sqrt(sum(v * v for v in q)) == pytest.approx(1.0, abs=1e-12)


def test_result_is_revalidated_and_raw_dicts_are_accepted(spec):
    raw = spec_to_dict(spec)
    raw["objects"][0]["scale"] = 3.0  # out of range: the raw dict does not parse ...
    out = apply_directives(raw, [Directive.scale("apple", 0.5)])  # ... until a directive brings it back
    assert isinstance(out, TaskSpec) and out.object("apple").scale == 1.5
    assert raw["objects"][0]["scale"] == 3.0  # the input mapping is untouched
    with pytest.raises(TaskSpecError, match="scale"):
        apply_directives(raw, [Directive.move("apple", "x", 0.1)])  # not fixed by the directives: still invalid


def test_unknown_object_in_apply(spec):
    with pytest.raises(DirectiveError, match="'pear'.*apple, bowl"):
        apply_directives(spec, [Directive.move("pear", "x", 0.1)])


def test_no_directives_is_identity(spec):
    assert apply_directives(spec, []) == spec
