"""Step 4, plan: the stages the solver runs: a skill on a target each, by ``motion_planning`` or ``RL`` with its
``control_joint``, and when the stage has done its job.

The answer is a YAML list of stages; it replaces the scene's stages and the whole spec is re-validated (stage
names unique and snake_case, skills, methods and control modes allowed, targets naming scene objects, success
conditions well formed). An RL stage whose answer declares no ``success`` gets the standard goal of its skill
(:mod:`generator.stage_goals`), so every stage a policy learns has a declared goal.
"""

from __future__ import annotations

import dataclasses
import json
import logging

from gendex_envs.errors import TaskSpecError
from gendex_envs.spec import (
    CONDITION_FIELDS,
    CONTROL_JOINT_MODES,
    STAGE_METHODS,
    TaskSpec,
    dump_task_spec,
    parse_task_spec,
    spec_to_dict,
)
from generator.backends.base import Backend
from generator.catalog_view import asset_dicts
from generator.errors import RetriesExhaustedError, SceneError
from generator.records import Proposal
from generator.stage_goals import stage_goal
from generator.steps.common import ask, parse_yaml_block
from generator.steps.propose import skill_list


def condition_list() -> str:
    """The condition types with their fields and meaning, one per line (for prompts)."""
    return "\n".join(f"  - {t}: {meaning} (fields: {', '.join(req)}"
                     + (f"; optional: {', '.join(opt)}" if opt else "") + ")"
                     for t, (req, opt, meaning) in CONDITION_FIELDS.items())

log = logging.getLogger(__name__)


def parse_plan(text: str, spec: TaskSpec) -> TaskSpec:
    stages = parse_yaml_block(text, "stage plan", SceneError)
    if isinstance(stages, dict) and "stages" in stages:
        stages = stages["stages"]
    if not isinstance(stages, list) or not stages:
        raise SceneError("the stage plan must be a non-empty YAML list of stages")
    raw = spec_to_dict(spec)
    articulated = {a["id"] for a in asset_dicts() if a["joints"]}
    kinds = {o["name"]: o["asset"] in articulated for o in raw["objects"]}
    for st in stages:
        if isinstance(st, dict) and st.get("method") == "RL" and not st.get("success"):
            goal = stage_goal(str(st.get("skill")), st.get("target"), raw["success"]["conditions"],
                              kinds.get(st.get("target"), False))
            if goal:
                st["success"] = goal
    raw["stages"] = stages
    try:
        return parse_task_spec(raw, source="stage plan", known_assets=[a["id"] for a in asset_dicts()])
    except TaskSpecError as exc:
        raise SceneError(str(exc)) from None


def plan_stages(backend: Backend, spec: TaskSpec, proposal: Proposal, *, max_attempts: int = 3) -> TaskSpec:
    proposal_dict = dataclasses.asdict(proposal)
    feedback = ""
    for attempt in range(max_attempts):
        context = {"spec": spec_to_dict(spec), "proposal": proposal_dict, "attempt": attempt}
        answer = ask(backend, "plan", context=context, feedback=feedback, task_yaml=dump_task_spec(spec),
                     proposal_json=json.dumps(proposal_dict, indent=2), control_joints=", ".join(CONTROL_JOINT_MODES),
                     stage_methods=", ".join(STAGE_METHODS), skills=skill_list(), stage_conditions=condition_list())
        try:
            return parse_plan(answer, spec)
        except SceneError as exc:
            log.info("plan attempt %d rejected: %s", attempt + 1, exc)
            feedback = str(exc)
    raise RetriesExhaustedError(f"no valid stage plan after {max_attempts} attempts; last reason: {feedback}")
