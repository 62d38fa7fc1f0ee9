"""The plan step declares every RL stage's goal: the model's own conditions when it gives them, else the standard
goal of the stage's skill."""

from __future__ import annotations

import pytest

from gendex_envs.spec import spec_to_dict
from generator.errors import SceneError
from generator.stage_goals import stage_goal
from generator.steps.plan import parse_plan

LIFT = [{"type": "lifted", "object": "apple", "min_height_m": 0.12}]
INSIDE = [{"type": "inside", "object": "apple", "target": "bowl"}]


@pytest.mark.parametrize(("skill", "articulated", "task", "expected"), [
    ("grasp", False, INSIDE, [{"type": "grasped", "object": "apple", "min_fingers": 1}]),
    ("grasp", True, INSIDE, [{"type": "grasped", "object": "apple", "part": "handle", "min_fingers": 3,
                              "thumb": False}]),
    ("lift", False, LIFT, [{"type": "grasped", "object": "apple", "min_fingers": 1},
                           {"type": "lifted", "object": "apple", "min_height_m": 0.12}]),
    ("lift", False, INSIDE, [{"type": "grasped", "object": "apple", "min_fingers": 1},
                             {"type": "lifted", "object": "apple", "min_height_m": 0.1}]),
    ("release", False, INSIDE, [*INSIDE, {"type": "grasped", "object": "apple", "negate": True}]),
    ("open", True, [{"type": "joint_open", "object": "apple", "min_fraction": 0.6}],
     [{"type": "joint_open", "object": "apple", "min_fraction": 0.6}]),
    ("close", True, [], [{"type": "joint_open", "object": "apple", "min_fraction": 0.8, "negate": True}]),
    ("twist", True, [{"type": "joint_open", "object": "apple", "min_fraction": 0.9}],
     [{"type": "joint_open", "object": "apple", "min_fraction": 0.9},
      {"type": "grasped", "object": "apple", "part": "handle"}]),
    ("reach", False, INSIDE, None),
    ("reorient", False, INSIDE, None),
])
def test_standard_goal_of_each_skill(skill, articulated, task, expected):
    assert stage_goal(skill, "apple", task, articulated) == expected


def test_the_plan_fills_rl_stages_without_a_goal_and_keeps_the_models_own(task_version):
    spec = task_version("PutAppleBowl", 0).spec
    plan = """```yaml
- {name: reach_apple, instruction: Reach., skill: reach, method: motion_planning, control_joint: arm, target: apple}
- {name: grasp_apple, instruction: Grasp., skill: grasp, method: RL, control_joint: hand, target: apple}
- {name: carry_apple, instruction: Carry., skill: carry, method: motion_planning, control_joint: arm, target: bowl}
- {name: release_apple, instruction: Let go., skill: release, method: RL, control_joint: hand, target: apple,
   success: [{type: released, object: apple}]}
```"""
    planned = parse_plan(plan, spec)
    reach, grasp, carry, release = planned.stages
    assert reach.success is None and carry.success is None  # planned motions declare no goal of their own
    assert [c.type for c in grasp.success] == ["grasped"]  # filled from the skill
    assert [c.type for c in release.success] == ["released"]  # the model's own, kept
    assert spec_to_dict(planned)["success"] == spec_to_dict(spec)["success"]


def test_a_plan_without_skills_is_fed_back(task_version):
    spec = task_version("PutAppleBowl", 0).spec
    with pytest.raises(SceneError, match=r"stages\[0\]\.skill: required field is missing"):
        parse_plan("```yaml\n- {name: a, instruction: A., method: RL, control_joint: hand, target: apple}\n```", spec)
