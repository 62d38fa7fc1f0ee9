"""Success that only purposeful hand work reaches: an ordered first step ("the fingers came to the handle", "the
object was held") before the end state counts.

Uniform random joint targets swing the arm through the workspace at every step. Its links slam doors and drawers
shut, knock lids and taps open, hit buttons and knock a ball across the table, and a success that reads only the end
state (the door shut) counts it: random actions solved 19 of the 52 tasks of the first ``gendex-lib-v2`` calibration
more than 5 % of the time (3-32 of 50; ``benchmarks/results/benchmark.md``). What they do not do is bring the
fingertips to a handle and keep them there, or hold an object: on development seeds (900 000-900 049, never a suite
seed; 17 articulated tasks) no random episode kept the fingertips within :data:`APPROACH_M` of a handle for more than
5 control steps, and none held a ball or block, while the planning executor kept them there 11-129 steps before the
end state held.

:func:`worked_by_hand` writes that first step into a task's ``success.sequence``: for a joint the success moves (a
door, drawer, lid, button, tap) ``fingertips_near`` its handle for :data:`APPROACH_STEPS` steps; for an object the
plan grasps and the success sets down somewhere, ``grasped`` for as long. The offline author's scene step applies
it to every task it writes, and :func:`publish_worked_by_hand` publishes it as the next version of a committed one.
"""

from __future__ import annotations

import dataclasses
import logging

import yaml

from gendex_envs.errors import TaskSpecError
from gendex_envs.spec import ConditionSpec, SequenceStepSpec, TaskSpec, dump_task_spec, load_task_spec
from gendex_envs.success import SET_DOWN_CONDITIONS
from gendex_envs.task_version import TaskLayout, TaskVersion, publish_derived
from generator.catalog_view import asset_dict

log = logging.getLogger(__name__)

APPROACH_M = 0.2
"""Mean fingertip distance from the handle's grip point (m) that counts as the fingers at the handle. On development
seeds the planning executor kept them within it for 11 steps or more before a button counted as pressed and for 23 or
more at doors, drawers, lids and taps; within 0.15 m its fingers were not at a box's lid on 2 of 4 seeds."""
APPROACH_STEPS = 8
"""Consecutive control steps (0.4 s at 20 Hz) the first step must hold: random actions passed the fingertips within
:data:`APPROACH_M` of a handle for at most 5 (the executor: 11 or more)."""
HELD_FINGERS = 1
"""Fingers besides the thumb that must touch an object for it to count as held (the grasp stages' own count)."""
JOINT_CONDITIONS = ("joint_open", "joint_at")
PLACE_CONDITIONS = (*SET_DOWN_CONDITIONS, "placed")


def _handled(spec: TaskSpec, name: str, joint: str | None) -> bool:
    """Whether object ``name`` is articulated and the joint (its main one when None) has a handle."""
    obj = next((o for o in spec.objects if o.name == name), None)
    if obj is None:
        return False
    asset = asset_dict(obj.asset)
    joints = asset.get("joints") or []
    if asset.get("kind") != "articulated" or not joints:
        return False
    j = joints[0] if joint is None else next((j for j in joints if j["name"] == joint), None)
    return j is not None and bool(j.get("handle_link"))


def first_steps(spec: TaskSpec) -> tuple[SequenceStepSpec, ...]:
    """The ordered first steps :func:`worked_by_hand` would add to ``spec`` (none when it needs none)."""
    conds = spec.success.conditions
    held = {c.object for c in conds if c.type == "grasped" and not c.negate}
    grasped = {st.target for st in spec.stages if st.skill == "grasp"}
    steps: list[SequenceStepSpec] = []
    seen: set = set()
    for c in conds:
        key = (c.object, c.joint)
        if c.type in JOINT_CONDITIONS and c.object not in held and key not in seen and _handled(spec, *key):
            seen.add(key)
            steps.append(SequenceStepSpec(
                description=f"The fingers have come to the {c.object.replace('_', ' ')}'s handle.",
                conditions=(ConditionSpec(type="fingertips_near", object=c.object, part="handle", joint=c.joint,
                                          max_dist_m=APPROACH_M),),
                hold_steps=APPROACH_STEPS))
        elif c.type in PLACE_CONDITIONS and not c.negate and c.object in grasped and c.object not in seen:
            seen.add(c.object)
            steps.append(SequenceStepSpec(
                description=f"The {c.object.replace('_', ' ')} has been held.",
                conditions=(ConditionSpec(type="grasped", object=c.object, min_fingers=HELD_FINGERS),),
                hold_steps=APPROACH_STEPS))
    order = {}
    for k, st in enumerate(spec.stages):
        order.setdefault(st.target, k)
    # in the order the plan works the objects ("close the box, then put the block on the tray": the lid's handle first)
    return tuple(sorted(steps, key=lambda s: order.get(s.conditions[0].object, len(spec.stages))))


def step_phrase(step: SequenceStepSpec) -> str:
    """A first step in a few words ("the fingers at the cabinet's handle for 8 steps")."""
    c = step.conditions[0]
    what = (f"the fingers at the {c.object.replace('_', ' ')}'s handle" if c.type == "fingertips_near"
            else f"the {c.object.replace('_', ' ')} held")
    return f"{what} for {step.hold_steps} steps"


def worked_by_hand(spec: TaskSpec) -> TaskSpec:
    """``spec`` with :func:`first_steps` as its ``success.sequence``. A spec that already orders its success (a
    composed task: "close the box, then put the potato in the bin") is returned unchanged: its own order already asks
    for the hand's work first."""
    if spec.success.sequence:
        return spec
    steps = first_steps(spec)
    if not steps:
        return spec
    log.info("success of %s: first %s", spec.name, "; ".join(s.description for s in steps))
    return dataclasses.replace(spec, success=dataclasses.replace(spec.success, sequence=steps))


def replace_success(text: str, spec: TaskSpec) -> str:
    """``text`` (a task spec's YAML) with its top-level ``success`` entry replaced by ``spec``'s and every other byte
    kept (comments, anchors the stages define)."""
    root = yaml.compose(text)
    pair = next(((k, v) for k, v in root.value if k.value == "success"), None) \
        if isinstance(root, yaml.MappingNode) else None
    if pair is None:
        raise NothingToHarden("the spec has no top-level 'success' entry")
    block = {"success": yaml.safe_load(dump_task_spec(spec))["success"]}
    dumped = yaml.safe_dump(block, sort_keys=False, default_flow_style=False, width=100, allow_unicode=True)
    start, end = pair[0].start_mark.index, pair[1].end_mark.index
    return text[:start] + dumped + text[end:].lstrip("\n")


class NothingToHarden(TaskSpecError):
    """The task's success already asks for the hand's work (or has nothing a flailing arm could reach)."""


def publish_worked_by_hand(source: TaskVersion) -> TaskVersion:
    """Publish ``v<N+1>`` of ``source``'s task with :func:`worked_by_hand` applied to its success (every other file
    copied; the solvability record is dropped, for ``gendex gate --write`` to measure again). Raises
    :class:`NothingToHarden` when the success would not change."""
    spec = source.spec
    harder = worked_by_hand(spec)
    if harder == spec:
        raise NothingToHarden(f"{source.env_id}: its success already asks for the hand's work first")

    def edit(out: TaskLayout) -> dict:
        text = out.spec.read_text()
        lines = text.splitlines(keepends=True)
        head = 0
        while head < len(lines) and lines[head].startswith("#"):
            head += 1
        note = (f"# v{source.version + 1}: success first needs "
                + "; ".join(step_phrase(s) for s in harder.success.sequence)
                + ", so that an arm flailing past the task does not solve it.\n")
        out.spec.write_text("".join(lines[:head]) + note + replace_success("".join(lines[head:]), harder))
        if load_task_spec(out.spec) != harder:
            raise NothingToHarden(f"{source.env_id}: the rewritten spec does not read back as written")
        out.record("solvability").unlink(missing_ok=True)
        steps = "; ".join(s.description for s in harder.success.sequence)
        return {"changed": [f"{out.spec.name}: success.sequence {steps}"],
                "reason": "Random joint targets reached the task's end state without the hand's work (the first v2 "
                          "suite calibration); success now first needs the fingers at the handle, or the object held."}

    return publish_derived(source, "revision", edit)


__all__ = ["APPROACH_M", "APPROACH_STEPS", "HELD_FINGERS", "NothingToHarden", "first_steps", "publish_worked_by_hand",
           "replace_success", "worked_by_hand"]
