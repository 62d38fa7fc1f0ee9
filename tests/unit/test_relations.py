"""The task language's spatial and joint-position conditions (``placed``, ``joint_at``): their tolerances, the
robot's point of view, and what the spec refuses."""

from __future__ import annotations

from types import SimpleNamespace

import pytest
import torch

from gendex_envs.errors import TaskSpecError
from gendex_envs.spec import CONDITION_DEFAULTS, REGIONS, ConditionSpec, parse_task_spec
from gendex_envs.success import REGION_AHEAD_M, REGION_MARGIN_M, condition_holds

GAP, MAX_GAP, OFFSET, ERR = (CONDITION_DEFAULTS[k] for k in ("min_gap_m", "max_gap_m", "max_offset_m", "max_error"))
EPS = 1e-4


class _Env:
    """What the two conditions read: poses (every object measured at its origin, as an articulated one is), the
    robot's base and a joint's opening. Positions are [N, 2] rows, one env per row."""

    def __init__(self, positions: dict[str, list[list[float]]], yaw_deg: float = 0.0, base=(-0.8, 0.0, 0.0),
                 opening: list[float] | None = None):
        self.xy = {k: torch.tensor(v, dtype=torch.float32) for k, v in positions.items()}
        self.num_envs = len(next(iter(self.xy.values())))
        self.device = torch.device("cpu")
        self.articulations = set(self.xy)
        self.task_spec = SimpleNamespace(robot=SimpleNamespace(base_pos_m=base, base_yaw_deg=yaw_deg))
        self.opening = torch.tensor(opening or [0.0] * self.num_envs)

    def obj_pose(self, name: str):
        xy = self.xy[name]
        return SimpleNamespace(p=torch.cat([xy, torch.zeros(len(xy), 1)], dim=1),
                               q=torch.tensor([[1.0, 0, 0, 0]] * len(xy)))

    def joint_open_fraction(self, name: str, joint: str | None = None) -> torch.Tensor:
        return self.opening


def holds(env: _Env, **kw) -> list[bool]:
    return condition_holds(env, ConditionSpec(type="placed", object="apple", **kw)).tolist()


def test_sides_are_the_robots_with_their_tolerances():
    """Seen from the robot at x = -0.8 facing +x: left is +y, in front of the bowl is towards the robot (-x),
    behind it away; each holds from min_gap_m to max_gap_m along its direction and within max_offset_m across."""
    bowl = [0.1, 0.0]
    for relation, direction, across in (("left_of", (0, 1), (1, 0)), ("right_of", (0, -1), (1, 0)),
                                        ("in_front_of", (-1, 0), (0, 1)), ("behind", (1, 0), (0, 1))):
        def at(along: float, off: float, direction=direction, across=across) -> list[float]:
            return [bowl[i] + along * direction[i] + off * across[i] for i in range(2)]

        rows = [at(GAP + EPS, 0), at(GAP - EPS, 0), at(MAX_GAP - EPS, 0), at(MAX_GAP + EPS, 0),
                at(0.15, OFFSET - EPS), at(0.15, -OFFSET + EPS), at(0.15, OFFSET + EPS), at(-0.15, 0)]
        env = _Env({"apple": rows, "bowl": [bowl] * len(rows)})
        assert holds(env, relation=relation, target="bowl") == [True, False, True, False, True, True, False,
                                                                 False], relation


def test_a_turned_robot_turns_left_and_right():
    """With the base turned 90 degrees (facing +y), its left is -x: the same apple is left of the bowl for one robot
    and in front of it for the other."""
    env = _Env({"apple": [[0.0, 0.2]], "bowl": [[0.15, 0.2]]}, yaw_deg=0.0)
    assert holds(env, relation="in_front_of", target="bowl") == [True]
    assert holds(env, relation="left_of", target="bowl") == [False]
    turned = _Env({"apple": [[0.0, 0.2]], "bowl": [[0.15, 0.2]]}, yaw_deg=90.0, base=(0.1, -0.8, 0.0))
    assert holds(turned, relation="left_of", target="bowl") == [True]
    assert holds(turned, relation="in_front_of", target="bowl") == [False]


def test_next_to_and_between():
    env = _Env({"apple": [[0.1 + GAP + EPS, 0.0], [0.1 + GAP - EPS, 0.0], [0.1, MAX_GAP - EPS], [0.1, -MAX_GAP - EPS]],
                "bowl": [[0.1, 0.0]] * 4})
    assert holds(env, relation="next_to", target="bowl") == [True, False, True, False]
    # between a bowl at y = -0.2 and a plate at y = +0.2: at least min_gap_m from each, within max_offset_m of the line
    rows = [[0.1, 0.0], [0.1, 0.2 - GAP - EPS], [0.1, 0.2 - GAP + EPS], [0.1, 0.25], [0.1 + OFFSET - EPS, 0.0],
            [0.1 + OFFSET + EPS, 0.0], [0.1, -0.2 + GAP - EPS]]
    env = _Env({"apple": rows, "bowl": [[0.1, -0.2]] * 7, "plate": [[0.1, 0.2]] * 7})
    assert holds(env, relation="between", target="bowl", other="plate") == [True, True, False, False, True, False,
                                                                             False]


@pytest.mark.parametrize("region", REGIONS)
def test_regions_of_the_table(region: str):
    """Regions are measured from the point REGION_AHEAD_M ahead of the base; a side region starts REGION_MARGIN_M
    off it, the centre ends there; corners are both sides at once."""
    cx, m = -0.8 + REGION_AHEAD_M, REGION_MARGIN_M
    offsets = {"left": (0, 1), "right": (0, -1), "near": (-1, 0), "far": (1, 0), "centre": (0, 0)}
    parts = region.split("_")
    dx = sum(offsets[p][0] for p in parts)
    dy = sum(offsets[p][1] for p in parts)
    inside = [cx + dx * (m + 0.02), dy * (m + 0.02)] if region != "centre" else [cx + m - EPS, -m + EPS]
    outside = [cx + dx * (m - 0.02), dy * (m - 0.02)] if region != "centre" else [cx + m + 0.02, 0.0]
    env = _Env({"apple": [inside, outside]})
    assert holds(env, relation="in_region", region=region) == [True, False]


def test_joint_at_a_fraction():
    env = _Env({"faucet": [[0.2, 0.0]] * 5}, opening=[0.0, ERR - EPS, ERR + EPS, 0.5, 1.0])
    at = lambda f, **kw: condition_holds(env, ConditionSpec(type="joint_at", object="faucet", fraction=f,  # noqa: E731
                                                            **kw)).tolist()
    assert at(0.0) == [True, True, False, False, False]  # off
    assert at(0.5, max_error=0.15) == [False, False, False, True, False]  # half-open
    assert at(1.0) == [False, False, False, False, True]  # on


# ------------------------------------------------------------------------------ the spec
def _spec(condition: dict) -> dict:
    objects = [{"name": n, "asset": "ycb_013_apple", "pos_m": [0.1, y, 0.0]}
               for n, y in (("apple", 0.0), ("bowl", 0.2), ("plate", -0.2))]
    return {"name": "PutAppleLeft", "instruction": "put the apple to the left of the bowl", "objects": objects,
            "stages": [{"name": "reach", "instruction": "reach", "skill": "reach", "method": "motion_planning",
                        "control_joint": "arm", "target": "apple"}],
            "success": {"description": "placed", "conditions": [condition]}}


@pytest.mark.parametrize("condition", [
    {"type": "placed", "object": "apple", "relation": "left_of", "target": "bowl"},
    {"type": "placed", "object": "apple", "relation": "between", "target": "bowl", "other": "plate",
     "min_gap_m": 0.08, "max_offset_m": 0.05},
    {"type": "placed", "object": "apple", "relation": "in_region", "region": "far_left"},
    {"type": "placed", "object": "apple", "relation": "next_to", "target": "bowl", "max_gap_m": 0.2},
    {"type": "joint_at", "object": "bowl", "fraction": 0.5, "max_error": 0.15},
])
def test_the_spec_takes_each_construct(condition: dict):
    spec = parse_task_spec(_spec(condition))
    assert spec.success.conditions[0].type == condition["type"]


@pytest.mark.parametrize("condition, pattern", [
    ({"type": "placed", "object": "apple", "relation": "left_of"}, r"target is required .* relation 'left_of'"),
    ({"type": "placed", "object": "apple", "relation": "between", "target": "bowl"}, r"other is required"),
    ({"type": "placed", "object": "apple", "relation": "in_region", "region": "left", "target": "bowl"},
     r"target = 'bowl' does not apply to relation 'in_region'"),
    ({"type": "placed", "object": "apple", "relation": "in_region"}, r"region is required"),
    ({"type": "placed", "object": "apple", "relation": "left_of", "target": "bowl", "region": "left"},
     r"region = 'left' does not apply"),
    ({"type": "placed", "object": "apple", "relation": "above", "target": "bowl"}, r"relation"),
    ({"type": "placed", "object": "apple", "relation": "in_region", "region": "top"}, r"region"),
    ({"type": "placed", "object": "apple", "relation": "left_of", "target": "bowl", "min_gap_m": 0.2,
      "max_gap_m": 0.1}, r"max_gap_m = 0.1 is not allowed; must be > min_gap_m \(0.2\)"),
    ({"type": "placed", "object": "apple", "relation": "left_of", "target": "bowl", "min_gap_m": -0.1},
     r"min_gap_m = -0.1 is not allowed; must be >= 0"),
    ({"type": "placed", "object": "apple", "relation": "between", "target": "bowl", "other": "bowl"},
     r"other = 'bowl' is not allowed; must be a third object"),
    ({"type": "placed", "object": "apple", "relation": "between", "target": "bowl", "other": "cup"},
     r"other"),
    ({"type": "joint_at", "object": "bowl", "fraction": 1.5}, r"fraction = 1.5 is not allowed; must be a fraction"),
    ({"type": "joint_at", "object": "bowl", "fraction": 0.5, "max_error": 0.7}, r"max_error = 0.7 is not allowed"),
    ({"type": "joint_at", "object": "bowl"}, r"fraction is required for type 'joint_at'"),
    ({"type": "joint_open", "object": "bowl", "min_fraction": 0.5, "relation": "left_of"},
     r"relation = 'left_of' does not apply to type 'joint_open'"),
])
def test_the_spec_refuses_what_a_construct_cannot_mean(condition: dict, pattern: str):
    with pytest.raises(TaskSpecError, match=pattern):
        parse_task_spec(_spec(condition))

