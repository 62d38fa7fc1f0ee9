"""Step 3, refine: measure the scene, critique it, apply directives by arithmetic, repeat until clean.

Each round the physical checks (:mod:`generator.critic.physical`) run in the simulator. Their violations come with
suggested directives, which are applied first: measurements beat opinions. When the backend sees images (a vision
model), the three renders and the measured findings go to the scene-analysis prompt, and the directives in its
answer are parsed and applied as well (``Scale_Action`` / ``Position_Action`` / ``Pose_Action``; never new numbers
from the model). A directive that cannot be applied is recorded with its reason. The loop ends when the checks
are clean and the critic asks for nothing, or after ``max_rounds`` rounds.
"""

from __future__ import annotations

import logging

from gendex_envs.errors import TaskSpecError
from gendex_envs.spec import TaskSpec, dump_task_spec
from generator.backends.base import Backend, ImagePart
from generator.errors import DirectiveError
from generator.records import CritiqueRound, RefineLog
from generator.render import VIEWS, render_spec
from generator.steps.common import ask

log = logging.getLogger(__name__)

MAX_ROUNDS = 4


def _vision_directives(backend: Backend, spec: TaskSpec, findings: str,
                       renders: dict[str, bytes] | None = None, seed: int = 0) -> tuple[str, list, list[str]]:
    from generator.critic.directives import parse_directives

    renders = renders if renders is not None else render_spec(spec, seed=seed)
    images = tuple(ImagePart(v, renders[v]) for v in VIEWS)
    names = [o.name for o in spec.objects]
    answer = ask(backend, "scene_analysis", images=images, context={"spec_yaml": dump_task_spec(spec)},
                 task_yaml=dump_task_spec(spec), object_names=", ".join(names), views=", ".join(VIEWS),
                 physical_findings=findings)
    try:
        return answer, parse_directives(answer, names), []
    except DirectiveError as exc:
        return answer, [], [str(exc)]


def apply_fixes(spec: TaskSpec, report, model_directives: list) -> tuple[TaskSpec, list[str], list[str]]:
    """Apply the measured fixes, then the critic's directives, one at a time; returns (spec, applied, rejected). A
    vessel moved, turned or scaled carries the pieces it holds (:func:`gendex_envs.pouring.refill`)."""
    from gendex_envs.pouring import refill, spec_fills
    from generator.critic.directives import apply_directives
    from generator.critic.joints import apply_joint_fix

    applied: list[str] = []
    rejected: list[str] = []
    directives = report.directives()
    directives += [d for d in model_directives if d not in directives]
    for d in directives:
        fills = spec_fills(spec)
        vessel = next((v for v, names in fills.items() if d.object in names), None)
        if vessel is not None:
            rejected.append(f"{d}: {d.object!r} is a piece GenDex lays in {vessel!r}; move, turn or scale the vessel")
            continue
        try:
            spec = refill(apply_directives(spec, [d]), fills)
            applied.append(str(d))
        except (DirectiveError, TaskSpecError) as exc:  # TaskSpecError: a vessel scaled too small for its pieces
            rejected.append(f"{d}: {exc}")
    for fix in report.joint_fixes():
        try:
            spec = apply_joint_fix(spec, fix)
            applied.append(f"Joint_State: {fix['object']} - {fix['joint']} {fix['value']}")
        except DirectiveError as exc:
            rejected.append(f"joint fix {fix}: {exc}")
    return spec, applied, rejected


def refine(backend: Backend, spec: TaskSpec, *, max_rounds: int = MAX_ROUNDS, seed: int = 0,
           renders: dict[str, bytes] | None = None) -> tuple[TaskSpec, RefineLog]:
    """Refine ``spec``; returns the refined spec and the log (violations before and after, every round).

    ``renders``: the views of ``spec`` when the caller has them already (the first vision round reuses them).
    """
    from generator.critic.physical_sim import check_scene

    rounds: list[CritiqueRound] = []
    before: int | None = None
    for r in range(max_rounds + 1):
        report = check_scene(spec, seed=seed)
        errors = report.errors
        if before is None:
            before = len(errors)
        if r == max_rounds:
            break
        analysis, model_directives, rejected = "", [], []
        if backend.sees_images:
            analysis, model_directives, rejected = _vision_directives(backend, spec, report.summary(),
                                                                      renders if r == 0 else None, seed)
        if not errors and not model_directives:
            break
        new_spec, applied, failed = apply_fixes(spec, report, model_directives)
        rounds.append(CritiqueRound(round=r, violations=tuple(f"{v.check}: {v.message}" for v in report.violations),
                                    analysis=analysis, directives=tuple(applied), rejected=tuple(rejected + failed)))
        log.info("refine round %d: %d violation(s), %d directive(s) applied", r, len(errors), len(applied))
        if not applied:
            break
        spec = new_spec
    return spec, RefineLog(rounds=tuple(rounds), violations_before=before or 0, violations_after=len(errors),
                           remaining=tuple(f"{v.check}: {v.message}" for v in errors))
