"""Stage 5, reward code: ``evaluate`` / ``compute_dense_reward`` / ``_get_obs_extra`` for every RL stage and the task.

For each RL stage (``stage_rewards/<stage>.py``) and for the whole task (``reward.py``) the backend is asked with
the environment-API, vectorised-patterns, function-generation and sub-stage prompts, plus the previous stage's
success specification. Every answer is untrusted: it is checked statically, then probed in the simulator in a
separate process (:mod:`generator.stages.validate`). A rejection is fed back together with the rejected code, a
bounded number of times.
"""

from __future__ import annotations

import ast
import logging
from dataclasses import dataclass
from pathlib import Path

import yaml

from gendex_envs.spec import TaskSpec, dump_task_spec, spec_to_dict
from generator.backends.base import Backend
from generator.errors import RetriesExhaustedError, RewardCodeError
from generator.prompts import render
from generator.records import Proposal, RewardAttempt
from generator.reward_library import roles_of
from generator.stages.common import ask, fenced

log = logging.getLogger(__name__)

TASK_MODULE = "reward.py"
STAGE_DIR = "stage_rewards"


@dataclass
class RewardSet:
    """Validated reward sources by path relative to the task folder, and every attempt's outcome."""

    modules: dict[str, str]
    attempts: list[RewardAttempt]
    reports: list[dict]


def _function_source(source: str, name: str) -> str:
    try:
        tree = ast.parse(source)
    except SyntaxError:
        return ""
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.name == name:
            return ast.get_source_segment(source, node) or ""
    return ""


def _previous_stage(spec: TaskSpec, i: int, modules: dict[str, str]) -> tuple[str, str]:
    if i == 0:
        return "", ""
    prev = spec.stages[i - 1]
    rel = f"{STAGE_DIR}/{prev.name}.py"
    if prev.method == "RL" and rel in modules:
        return f"evaluate() of stage {prev.name}", _function_source(modules[rel], "evaluate")
    return f"{prev.method} stage {prev.name}", yaml.safe_dump(spec_to_dict(spec)["stages"][i - 1], sort_keys=False)


def _ask_module(backend: Backend, spec: TaskSpec, proposal: Proposal, stage_index: int | None,
                modules: dict[str, str], previous: str, feedback: str, attempt: int) -> str:
    if stage_index is None:
        name, instruction, joint = "whole_task", spec.instruction, "both"
        source_type, content = "", ""
    else:
        st = spec.stages[stage_index]
        name, instruction, joint = st.name, st.instruction, st.control_joint
        source_type, content = _previous_stage(spec, stage_index, modules)
    task_yaml = dump_task_spec(spec)
    variables = dict(
        env_api=render("env_api"), patterns=render("patterns"),
        substage=render("substage", task_yaml=task_yaml, stage_name=name, stage_instruction=instruction,
                        control_joint=joint, full_instruction=spec.instruction,
                        success_description=spec.success.description),
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

    ``task_dir`` must already hold ``task.yaml``; validated modules are left in it.
    """
    from generator.stages.validate import check_reward_source, validate_task  # noqa: PLC0415

    targets: list[tuple[str, int | None]] = [(f"{STAGE_DIR}/{s.name}.py", i) for i, s in enumerate(spec.stages)
                                             if s.method == "RL"]
    targets.append((TASK_MODULE, None))
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
            source = _ask_module(backend, spec, proposal, idx, modules, previous, feedback, attempt)
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
