"""Step 5, reward code: ``evaluate`` / ``compute_dense_reward`` / ``_get_obs_extra`` for every RL stage and the task.

For each RL stage and for the whole task the backend is asked for a reward module (where it goes is the task
layout's business, :class:`~gendex_envs.task_version.TaskLayout`) with the environment-API, vectorised-patterns,
function-generation and sub-stage prompts, the stage's declared success conditions and the previous stage's. The
module shapes the reward and may declare failure; success stays the spec's. Every answer is untrusted: it is
checked statically, then probed in the simulator in a separate process (:mod:`generator.steps.validate`). A
rejection is fed back together with the rejected code, a bounded number of times.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import yaml

from gendex_envs.spec import TaskSpec, dump_task_spec, omit_unset, spec_to_dict
from gendex_envs.task_version import TaskLayout
from generator.backends.base import Backend
from generator.errors import RetriesExhaustedError, RewardCodeError
from generator.prompts import render
from generator.records import Proposal, RewardAttempt
from generator.reward_library import roles_of
from generator.steps.common import ask, fenced

log = logging.getLogger(__name__)


@dataclass
class RewardSet:
    """Validated reward sources by path relative to the task folder, and every attempt's outcome."""

    modules: dict[str, str]
    attempts: list[RewardAttempt]
    reports: list[dict]


def _conditions_yaml(conditions: list[dict]) -> str:
    return yaml.safe_dump(omit_unset(conditions), sort_keys=False, default_flow_style=None, width=110).strip()


def _stage_conditions(spec: TaskSpec, i: int) -> list[dict]:
    return spec_to_dict(spec)["stages"][i]["success"] or spec_to_dict(spec)["success"]["conditions"]


def _previous_stage(spec: TaskSpec, i: int) -> tuple[str, str]:
    if i == 0:
        return "", ""
    prev = spec.stages[i - 1]
    return f"the success conditions of {prev.method} stage {prev.name}", _conditions_yaml(_stage_conditions(spec,
                                                                                                         i - 1))


def _ask_module(backend: Backend, spec: TaskSpec, proposal: Proposal, stage_index: int | None,
                previous: str, feedback: str, attempt: int) -> str:
    if stage_index is None:
        name, instruction, joint = "whole_task", spec.instruction, "both"
        source_type, content = "", ""
        success = spec_to_dict(spec)["success"]["conditions"]
    else:
        st = spec.stages[stage_index]
        name, instruction, joint = st.name, st.instruction, st.control_joint
        source_type, content = _previous_stage(spec, stage_index)
        success = _stage_conditions(spec, stage_index)
    task_yaml = dump_task_spec(spec)
    variables = dict(
        env_api=render("env_api"), patterns=render("patterns"),
        substage=render("substage", task_yaml=task_yaml, stage_name=name, stage_instruction=instruction,
                        control_joint=joint, full_instruction=spec.instruction,
                        success_description=spec.success.description, stage_success=_conditions_yaml(success)),
        previous_stage=render("previous_stage", source_type=source_type, content=content),
        previous_function=render("previous_function", previous_code=previous, feedback=feedback),
    )
    context = {"spec": spec_to_dict(spec), "stage": None if stage_index is None else name,
               "roles": roles_of({"objects": [o.__dict__ for o in proposal.objects]}), "attempt": attempt,
               "feedback": feedback}
    answer = ask(backend, "function_generation", context=context, **variables)
    return fenced(answer, "python").strip() + "\n"


def write_rewards(backend: Backend, spec: TaskSpec, proposal: Proposal, task_dir: Path, *,
                  max_attempts: int = 3, probe_steps: int = 20, timeout_s: float = 60.0) -> RewardSet:
    """Write, validate and (on rejection) rewrite every reward module of ``spec`` in ``task_dir``.

    ``task_dir`` must already hold the task spec; validated modules are left in it.
    """
    from generator.steps.validate import check_reward_source, validate_task

    layout = TaskLayout(task_dir)
    targets: list[tuple[str, int | None]] = [(layout.relative(layout.stage_reward(s.name)), i)
                                             for i, s in enumerate(spec.stages) if s.method == "RL"]
    targets.append((layout.relative(layout.reward), None))
    modules: dict[str, str] = {}
    attempts: list[RewardAttempt] = []
    pending = {rel: ("", "") for rel, _ in targets}  # rel -> (previous code, feedback)
    reports: list[dict] = []
    for attempt in range(max_attempts):
        written: list[str] = []
        for rel, idx in targets:
            if rel not in pending:
                continue
            previous, feedback = pending[rel]
            source = _ask_module(backend, spec, proposal, idx, previous, feedback, attempt)
            try:
                check_reward_source(source, filename=rel)
            except RewardCodeError as exc:
                attempts.append(RewardAttempt(rel, attempt, False, str(exc)))
                pending[rel] = (source, str(exc))
                continue
            path = task_dir / rel
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(source)
            modules[rel] = source
            written.append(rel)
        if written:
            report = validate_task(task_dir, [task_dir / r for r in written], steps=probe_steps, timeout_s=timeout_s)
            for rel, outcome in zip(written, report.modules, strict=True):
                if outcome.ok:
                    attempts.append(RewardAttempt(rel, attempt, True, "passed the static checks and the probe"))
                    p = outcome.probe
                    reports.append({"module": rel, "steps": p.steps, "reward_min": round(p.reward_min, 4),
                                    "reward_max": round(p.reward_max, 4), "reward_mean": round(p.reward_mean, 4),
                                    "success_rate": p.success_rate, "fail_rate": p.fail_rate,
                                    "obs_extra": p.obs_extra, "warnings": p.warnings})
                    pending.pop(rel)
                else:
                    problem = f"{outcome.error_type}: {outcome.error}"
                    attempts.append(RewardAttempt(rel, attempt, False, problem))
                    pending[rel] = (modules.pop(rel), problem)
                    (task_dir / rel).unlink()
        if not pending:
            return RewardSet(modules, attempts, reports)
        log.info("reward attempt %d: %d module(s) rejected: %s", attempt + 1, len(pending),
                 "; ".join(f"{r}: {fb}" for r, (_, fb) in pending.items()))
    rel, (_, fb) = next(iter(pending.items()))
    raise RetriesExhaustedError(f"reward module {rel} still rejected after {max_attempts} attempts: {fb}")
