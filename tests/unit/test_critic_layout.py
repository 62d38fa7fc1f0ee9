"""Where the critic's penetration fix puts an object (generator.critic.layout): never in front of a door a stage
works, on another object, off the table or out of reach, when a free spot is near."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from gendex_envs.spec import parse_task_spec, spec_to_dict
from generator.critic.directives import apply_directives
from generator.critic.layout import (
    FRONT_ZONE_MAX_M,
    FRONT_ZONE_MIN_M,
    Room,
    axis_moves,
    choose_move,
    front_zone,
    separating_move,
)
from generator.critic.physical import _place, check_scene_static, randomization_xy, room_for

SCENE = Path(__file__).parents[1] / "data" / "tasks" / "CloseMicrowaveThenPutCanInPot.yaml"
"""Batch 58117's proposal before the critic: the can overlaps the pot, the microwave's door is to be pressed shut."""


@pytest.fixture(scope="module")
def spec():
    return parse_task_spec(yaml.safe_load(SCENE.read_text()), source=str(SCENE))


def footprint(spec, name):
    """xy (lo, hi) of an object's box widened by its randomization."""
    p = _place(spec.object(name))
    j = np.asarray(spec.object(name).randomize.xy_m)
    return p.lo[:2] - j, p.hi[:2] + j


def meets(a, b) -> bool:
    return bool(np.all(a[1] > b[0]) and np.all(b[1] > a[0]))


def test_the_fix_keeps_the_can_out_of_the_front_of_the_microwave_whose_door_a_stage_shuts(spec):
    placed = {o.name: _place(o) for o in spec.objects}
    can, pot = placed["can"], placed["pot"]
    (zone,) = room_for(spec, placed, ("can", "pot")).zones
    # the move along the centre line (the only one before) ends in front of the door, at every reset
    line = separating_move(can.lo, can.hi, pot.lo, pot.hi, 0.0, randomization_xy(can, pot))
    lo, hi = footprint(spec, "can")
    assert meets(zone, (lo + line, hi + line))

    (v,) = check_scene_static(spec).violations
    assert (v.check, v.object, v.other) == ("penetration", "can", "pot")
    fixed = apply_directives(spec, v.fix)
    assert check_scene_static(fixed).violations == []
    assert not meets(zone, footprint(fixed, "can"))
    assert not meets(footprint(fixed, "can"), footprint(fixed, "pot"))  # apart at every reset
    # the shortest way that is free: one axis, less far than the centre line's 34 cm
    shift = np.subtract(fixed.object("can").pos_m, spec.object("can").pos_m)[:2]
    assert np.count_nonzero(shift) == 1 and np.linalg.norm(shift) < np.linalg.norm(line)


def test_an_articulated_object_no_stage_works_has_no_front_zone(spec):
    raw = spec_to_dict(spec)
    raw["stages"] = raw["stages"][2:]
    raw["success"]["conditions"] = raw["success"]["conditions"][1:]
    idle = parse_task_spec(raw)
    placed = {o.name: _place(o) for o in idle.objects}
    room = room_for(idle, placed, ("can", "pot"))
    assert room.zones == () and len(room.obstacles) == 1  # the microwave is still an obstacle


def test_front_zone_lies_before_the_front_face_as_deep_as_the_object_is_wide_within_limits():
    eye = np.eye(3)
    z = front_zone((-0.2, -0.1, 0.0), (0.2, 0.1, 0.5), eye, (0.5, 0.0, 0.0), (0.0, 0.0))
    np.testing.assert_allclose(z, [[0.1, -0.1], [0.3, 0.1]])  # 20 cm wide: 20 cm deep
    knob = front_zone((-0.05, -0.03, 0.0), (0.05, 0.03, 0.2), eye, (0.5, 0.0, 0.0), (0.0, 0.0))
    np.testing.assert_allclose(knob, [[0.45 - FRONT_ZONE_MIN_M, -0.03], [0.45, 0.03]])  # the shallowest
    wide = front_zone((-0.2, -0.4, 0.0), (0.2, 0.4, 0.5), eye, (0.5, 0.0, 0.0), (0.02, 0.03))
    np.testing.assert_allclose(wide, [[0.3 - FRONT_ZONE_MAX_M - 0.02, -0.43], [0.32, 0.43]])
    turned = front_zone((-0.2, -0.1, 0.0), (0.2, 0.1, 0.5), eye, (0.5, 0.0, 0.0), (0.0, 0.0), yaw_deg=15.0)
    assert np.all(turned[0] < z[0]) and np.all(turned[1] > z[1])  # swept over the yaw randomization


def test_room_says_why_a_box_does_not_fit():
    room = Room((0.8, 0.6), (-0.8, 0.0), (0.4, 1.2), obstacles=((np.array([0.2, 0.2, 0.0]),
                                                                 np.array([0.3, 0.3, 0.1])),),
                zones=(np.array([[0.0, -0.5], [0.1, -0.4]]),))
    box = np.array([-0.02, -0.02, 0.0]), np.array([0.02, 0.02, 0.1])

    def at(x, y, j=(0.0, 0.0)):
        return room.why_not(box[0] + [x, y, 0], box[1] + [x, y, 0], j)

    assert at(0.0, 0.0) is None
    assert at(0.0, 0.0, (0.05, 0.05)) is None
    assert at(0.79, 0.0) == "off the table"
    assert at(0.0, 0.57, (0.0, 0.02)) == "off the table"  # its randomization would take it over the edge
    assert at(-0.6, 0.0) == "out of reach"  # over the base
    assert at(0.6, 0.55) == "out of reach"
    assert at(0.25, 0.25) == "on another object"
    assert at(0.15, 0.15, (0.04, 0.04)) == "on another object"
    assert at(0.05, -0.45) == "in front of an articulated object the task works"


def test_choose_move_takes_the_centre_line_when_free_and_falls_back_to_it_when_nothing_is():
    mover = np.array([0.0, 0.0, 0.0]), np.array([0.1, 0.1, 0.1])
    other = np.array([0.05, 0.08, 0.0]), np.array([0.25, 0.3, 0.1])
    line = separating_move(*mover, *other, 0.0, (0.0, 0.0))
    free = Room((0.8, 0.6), (-0.8, 0.0), (0.0, 2.0))
    np.testing.assert_allclose(choose_move(*mover, *other, free, 0.0, (0.0, 0.0), (0.0, 0.0)), line)
    # the centre line (down and left) ends in a zone: the shortest free axis move is taken instead
    zone = np.array([[-0.2, -0.2], [0.0, 0.0]])
    blocked = Room((0.8, 0.6), (-0.8, 0.0), (0.0, 2.0), zones=(zone,))
    d = choose_move(*mover, *other, blocked, 0.0, (0.0, 0.0), (0.0, 0.0))
    assert np.count_nonzero(d) == 1 and blocked.why_not(mover[0] + np.r_[d, 0], mover[1] + np.r_[d, 0], (0, 0)) \
        is None
    assert any(np.allclose(d, a) for a in axis_moves(*mover, *other, (0.0, 0.0)))
    # nowhere fits (a tiny table): the centre line is kept, and the next critic round still sees the problem
    nowhere = Room((0.05, 0.05), (-0.8, 0.0), (0.0, 2.0))
    np.testing.assert_allclose(choose_move(*mover, *other, nowhere, 0.0, (0.0, 0.0), (0.0, 0.0)), line)


def test_axis_moves_clear_the_other_box_by_the_margin_and_both_randomizations():
    mover = np.array([0.0, 0.0, 0.0]), np.array([0.1, 0.1, 0.1])
    other = np.array([0.05, 0.08, 0.0]), np.array([0.25, 0.3, 0.1])
    moves = axis_moves(*mover, *other, (0.02, 0.03))
    assert len(moves) == 4 and [float(np.abs(d).sum()) for d in moves] == sorted(float(np.abs(d).sum())
                                                                                 for d in moves)
    for d in moves:
        lo, hi = mover[0][:2] + d, mover[1][:2] + d
        gap = np.maximum(other[0][:2] - hi, lo - other[1][:2]).max()
        axis = int(np.flatnonzero(d)[0])
        assert gap == pytest.approx(0.01 + (0.02, 0.03)[axis])
