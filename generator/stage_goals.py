"""Standard success conditions of a stage, by its skill: what the plan step declares when the model gives none.

A stage's success is data in the spec (``stages[k].success``, :mod:`gendex_envs.success`). The templates below
follow the reference tasks: a grasp holds the target with the thumb against two fingers (a hook on a handle: three
fingers, no thumb), a lift holds it at the task's lift height, a release leaves the task's success met with the hand
let go, an open, close or turn moves the joint past the task's fraction (a turn back below it when the task's
condition is the joint shut: turning off; to the task's ``joint_at`` fraction when it has one; a twist's unscrewed
cap ends in the hand), a push meets the task's condition on the pushed object, a wipe the task's wipe of its area, a
pour the task's pour into its container.
Skills without a template (reach, carry, place, reorient) declare nothing, so the stage succeeds with the task.
"""

from __future__ import annotations

from typing import Any

from gendex_envs.spec import JOINT_SKILLS

LIFT_M = 0.1
"""Lift height when the task states none (a ``lifted`` success condition states it)."""
OPEN_FRACTION = 0.8
"""Joint opening when the task states none (a ``joint_open`` success condition states it)."""


HELD = {"type": "grasped", "min_fingers": 1}
"""A rigid object is held when the thumb and at least one finger press on it: what benchmarks/grasp.py measures as a
hold (a precision pinch holds with thumb and index alone; the default two fingers rejected those)."""


def _task_value(task_conditions: list[dict], kind: str, obj: str, key: str, default: float) -> float:
    for c in task_conditions:
        if c.get("type") == kind and c.get("object") == obj and c.get(key) is not None:
            return float(c[key])
    return default


def _shuts(task_conditions: list[dict], obj: str) -> bool:
    """Whether the task's joint condition on ``obj`` is the joint shut (a turn off)."""
    return any(c.get("type") == "joint_open" and c.get("object") == obj and c.get("negate") for c in task_conditions)


def stage_goal(skill: str, target: str | None, task_conditions: list[dict], articulated: bool) -> list[dict] | None:
    """The standard ``success`` of a stage (a list of condition mappings), or None when the skill has none."""
    if target is None:
        return None
    if skill == "grasp":
        if articulated:
            return [{"type": "grasped", "object": target, "part": "handle", "min_fingers": 3, "thumb": False}]
        return [dict(HELD, object=target)]
    if skill == "lift":
        h = _task_value(task_conditions, "lifted", target, "min_height_m", LIFT_M)
        return [dict(HELD, object=target), {"type": "lifted", "object": target, "min_height_m": h}]
    if skill == "release":  # the task's conditions on the released object (all of them if none names it)
        mine = [c for c in task_conditions if c.get("object") == target] or task_conditions
        return [*(dict(c) for c in mine), {"type": "grasped", "object": target, "negate": True}]
    if skill in JOINT_SKILLS:
        at = [dict(c) for c in task_conditions if c.get("type") == "joint_at" and c.get("object") == target]
        if at:  # set part way (open halfway, turn to an angle): the stage ends where the task does
            return at
        frac = _task_value(task_conditions, "joint_open", target, "min_fraction", OPEN_FRACTION)
        cond: dict[str, Any] = {"type": "joint_open", "object": target, "min_fraction": frac}
        shuts = skill == "close" or (skill != "open" and _shuts(task_conditions, target))
        if skill == "twist" and not shuts:  # unscrewed with the cap in the hand (generator.steps.scene)
            return [cond, {"type": "grasped", "object": target, "part": "handle"}]
        return [cond | {"negate": True}] if shuts else [cond]
    if skill == "place":  # the task's conditions with this target: the held object set on it
        return [dict(c) for c in task_conditions if c.get("target") == target] or None
    if skill == "push":  # the task's own condition on the pushed object (near the goal mark)
        return [dict(c) for c in task_conditions if c.get("object") == target] or None
    if skill == "hang":  # hung on the peg, still in the hand: the release stage ends where the task does
        return None
    if skill == "pour":  # the task's pour into this container
        return [dict(c) for c in task_conditions if c.get("type") == "poured" and c.get("target") == target] or None
    if skill == "wipe":  # the task's wipe of this area
        return [dict(c) for c in task_conditions if c.get("type") == "wiped" and c.get("target") == target] or None
    if skill == "flip":  # turned over, still in the hand: the release stage ends where the task does
        return [dict(c) for c in task_conditions if c.get("type") == "flipped" and c.get("object") == target] or None
    return None
