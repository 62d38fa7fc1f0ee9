"""The critic's structure_room check (generator.critic.room): a scene's fixed structures must leave the arm room, and
a structure that does not is an error whose message names it."""

from __future__ import annotations

import dataclasses

import pytest

from gendex_envs.registry import REFERENCE_TASKS
from gendex_envs.scene_spec import parse_scene
from gendex_envs.scene_styles import STYLES
from generator.critic.physical import REACH_MAX_M, check_scene_static
from generator.critic.room import ARM_ROOM_HEIGHT_M, BASE_CLEAR_M


@pytest.fixture(scope="module")
def specs(task_version):
    """The reference tasks' newest versions without their scenes (each test gives the scene it checks)."""
    return {name: dataclasses.replace(task_version(name).spec, scene=None) for name in REFERENCE_TASKS}


def _with(spec, scene):
    return dataclasses.replace(spec, scene=parse_scene(scene))


def _room(spec, scene):
    report = check_scene_static(_with(spec, scene))
    return report, report.by_check("structure_room")


def _one(kind: str, **where) -> dict:
    return {"style": "lab", "structures": [{"name": "thing", "kind": kind, **where}]}


def test_every_style_leaves_the_arm_room_on_every_reference_task(specs):
    for name, spec in specs.items():
        for style in STYLES:
            report, found = _room(spec, style)
            assert found == [], (name, style, [v.message for v in found])
            meas = report.measurements["structure_room"]
            assert set(meas) == {s.name for s in STYLES[style].structures}
            assert all(m["nearest_base_m"] > BASE_CLEAR_M and m["in_arm_room_m"] == 0.0 for m in meas.values())


def test_a_task_without_a_scene_has_nothing_to_check(specs):
    report = check_scene_static(specs["PutAppleBowl"])
    assert report.by_check("structure_room") == [] and report.measurements["structure_room"] == {}


def test_a_shelf_on_the_table_in_reach_leaves_the_arm_no_room(specs):
    report, found = _room(specs["PutAppleBowl"], _one("shelf", pos_m=[0.1, 0.0, 0.0]))
    assert not report.ok
    room = [v for v in found if v.other == "structure:thing"]
    assert len(room) == 1
    v = room[0]
    assert v.severity == "error" and v.fix == () and v.object is None
    assert "'thing' (shelf)" in v.message and "arm's room over the table" in v.message
    assert f"within {REACH_MAX_M} m" in v.message and f"{ARM_ROOM_HEIGHT_M} m above" in v.message
    assert v.measured == pytest.approx(0.35)  # the shelf is 0.35 m deep: its shortest way out of the room
    # it also stands on the apple's and the bowl's start regions, where the env refuses to build it
    assert {v.other for v in found} == {"structure:thing", "apple", "bowl"}
    assert all("start region" in v.message for v in found if v.other != "structure:thing")


def test_a_cabinet_hung_over_the_table_is_in_the_arms_room(specs):
    """A wall cabinet hung 0.6-1.3 m above the near half of the table: in the room, which reaches 0.9 m up."""
    _, found = _room(specs["OpenCabinet"], _one("wall_cabinet", pos_m=[-0.2, 0.0, 0.6]))
    v = next(v for v in found if v.other == "structure:thing")
    assert v.measured == pytest.approx(ARM_ROOM_HEIGHT_M - 0.6)


def test_a_structure_by_the_robot_base_is_flagged(specs):
    _, found = _room(specs["PutAppleBowl"], _one("filing_cabinet", pos_m=[-0.8, 0.3, 0.0], on_floor=True))
    assert len(found) == 1
    assert "stands 0.07 m from the robot base's axis" in found[0].message and found[0].limit == BASE_CLEAR_M


def test_beyond_the_reach_or_beside_the_table_a_structure_may_stand(specs):
    """A splashback along the far edge (1.55 m from the base) and a counter beside the table leave the arm room."""
    far = _one("backsplash", pos_m=[0.0, 0.0, 0.0], anchor="far_edge")
    beside = _one("counter", pos_m=[0.0, 0.4, 0.0], anchor="left_edge", on_floor=True, yaw_deg=90.0)
    for scene in (far, beside):
        report, found = _room(specs["PutAppleBowl"], scene)
        assert found == [], [v.message for v in found]
        assert report.measurements["structure_room"]["thing"]["in_arm_room_m"] == 0.0


def test_the_simulator_check_does_not_build_a_scene_whose_structures_leave_no_room(specs, monkeypatch):
    """The env refuses a structure on an object's start region: the simulator check reports the static findings and
    builds nothing."""
    import generator.critic.physical_sim as sim

    def no_env(*args, **kwargs):
        raise AssertionError("the scene was built")

    monkeypatch.setattr(sim, "_sim_checks", no_env)
    report = sim.check_scene(_with(specs["PutAppleBowl"], _one("shelf", pos_m=[0.1, 0.0, 0.0])))
    assert report.mode == "sim" and not report.ok
    assert {v.other for v in report.by_check("structure_room")} == {"structure:thing", "apple", "bowl"}
