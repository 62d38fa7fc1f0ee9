"""The generator pipeline: propose -> scene -> render -> critique/refine -> plan -> reward code -> validate -> commit.

Each step is a function of typed records (:mod:`generator.steps`); this module runs them in order for one task at a
time, saves every record in the task's draft folder, and publishes it atomically as a task version at the end
(:func:`gendex_envs.task_version.publish`). Every request and answer is recorded to the version's transcript;
replaying it reproduces the task files byte for byte.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from gendex_envs.spec import dump_task_spec
from gendex_envs.task_version import TaskLayout, TaskVersion, clean_drafts, new_draft, publish
from generator.backends.base import Backend
from generator.backends.transcript import RecordingBackend
from generator.catalog_view import asset_dicts
from generator.errors import GeneratorError
from generator.instruction import Reading, read_instruction
from generator.novelty import ExistingTask, Novelty, existing_tasks, spec_signature
from generator.records import GenerationInfo, to_json
from generator.render import render_spec
from generator.steps.gate import GATE_ATTEMPTS, GateResult, run_gate
from generator.steps.plan import plan_stages
from generator.steps.propose import propose
from generator.steps.refine import refine
from generator.steps.reward import write_rewards
from generator.steps.scene import N_CANDIDATES, write_scene

log = logging.getLogger(__name__)

MAX_TASK_ATTEMPTS = 3
"""Proposals tried per task before giving up on it (a scene that cannot be refined clean starts over)."""


def generator_version() -> str:
    try:
        return version("gendex")
    except PackageNotFoundError:
        return "0+unknown"


@dataclass(frozen=True)
class TaskSummary:
    """One generated task, for the CLI's per-task summary."""

    committed: TaskVersion
    candidate_violations: tuple[float, ...]
    """Static-check violations of each scene candidate (the best one is refined)."""
    violations_before: int
    violations_after: int
    refine_rounds: int
    seconds: float
    proposals_tried: int = 1
    """Proposals this task took: a scene refinement could not make sound is dropped and a new task proposed."""
    substitutions: dict[str, str] = dataclasses.field(default_factory=dict)
    """Requested object -> catalog asset used instead (human-guided mode; also in the proposal record)."""
    dropped: tuple[str, ...] = ()
    """Proposals dropped on the way, each with its reason (a scene left unsound, the solvability gate failed)."""
    gate: GateResult | None = None
    """The solvability gate's measurement of the committed task (None when the gate was skipped)."""


def author_name(backend: Backend) -> str:
    """The backend that wrote the answers: through a recorder, the wrapped one; on replay, the recorded one."""
    recorded = getattr(backend, "recorded_backend", None)
    if recorded:
        return str(recorded)
    inner = getattr(backend, "inner", None)
    return author_name(inner) if inner is not None else backend.name


def _write(path: Path, data: str | bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(data, bytes):
        path.write_bytes(data)
    else:
        path.write_text(data)


def _task_roots(root: Path) -> list[Path]:
    """The output folder and the repository's task folder: where existing tasks live."""
    from gendex_envs.registry import REPO_TASKS_DIR

    return sorted({Path(root), REPO_TASKS_DIR})


def _existing_names(root: Path) -> tuple[str, ...]:
    names = set()
    for r in _task_roots(root):
        if r.is_dir():
            names |= {p.name for p in r.iterdir() if p.is_dir() and not p.name.startswith(".")}
    return tuple(sorted(names))


def generate_task(backend_factory: Callable[[], Backend], root: Path, *, index: int, seed: int,
                  instruction: str | None, command: str, existing: tuple[str, ...] = (),
                  candidates: int = N_CANDIDATES, reading: Reading | None = None,
                  gate_attempts: int = GATE_ATTEMPTS, novelty: Novelty | None = None,
                  dropped_names: set[str] | None = None, gate_workers: int = 1) -> TaskSummary:
    """Generate, validate, gate and commit one task with a fresh ``backend_factory()``, recording every exchange.

    With an ``instruction``: its ``reading`` (read here when not given; :class:`~generator.instruction.
    InstructionError` before anything is written when it asks for what GenDex cannot do). A proposal whose scene
    cannot be refined clean, or whose draft the solver does not solve on ``gate_attempts`` unseen seeds
    (:mod:`generator.steps.gate`; 0 skips the gate), is dropped with its reason and the next one is asked for, told
    what failed; after :data:`MAX_TASK_ATTEMPTS` proposals :class:`GeneratorError` lists every reason.
    ``novelty``: the existing tasks an autonomous proposal may not duplicate (:mod:`generator.novelty`).
    ``dropped_names``: names of proposals dropped so far in the batch (not proposed again); this task's are added.
    ``gate_workers``: processes running the gate's attempts (the same result as one)."""
    dropped_names = set() if dropped_names is None else dropped_names
    t0 = time.perf_counter()
    if instruction is not None and reading is None:
        reading = read_instruction(instruction, asset_dicts())
    draft = new_draft(root)
    files = TaskLayout(draft)
    try:
        source = backend_factory()
        backend = RecordingBackend(source, files.transcript)
        reasons: list[str] = []
        dropped: list[str] = []
        for attempt in range(MAX_TASK_ATTEMPTS):
            _clear_draft(draft, keep=files.transcript)
            proposal, rejected = propose(backend, index=index + 1000 * attempt, existing=existing,
                                         instruction=instruction, reading=reading,
                                         feedback="; ".join(dropped[-2:]), novelty=novelty)
            for phrase, asset in proposal.substitutions.items():
                log.warning("task %d: substituted %s for %r (recorded with the proposal)", index, asset, phrase)
            reasons += rejected
            spec, scenes = write_scene(backend, proposal, index=index + 1000 * attempt, n_candidates=candidates)
            before = render_spec(spec, seed=seed)
            refined, refine_log = refine(backend, spec, seed=seed, renders=before)
            if refine_log.remaining:
                dropped.append(f"{proposal.name}: {len(refine_log.remaining)} violation(s) left after refinement "
                               f"({'; '.join(refine_log.remaining[:3])})")
                log.info("task %d attempt %d: %s; proposing again", index, attempt + 1, dropped[-1])
                existing = (*existing, proposal.name)
                dropped_names.add(proposal.name)
                continue
            planned = plan_stages(backend, refined, proposal)
            header = (f"# Generated by GenDex {generator_version()} ({author_name(backend)} backend, seed {seed}, "
                      f"task {index}).\n"
                      f"# {proposal.description}\n")
            _write(files.spec, header + dump_task_spec(planned))
            rewards = write_rewards(backend, planned, proposal, draft)
            gate = run_gate(draft, proposal.name, gate_attempts, workers=gate_workers) if gate_attempts else None
            if gate is not None and not gate.passed:
                dropped.append(f"{proposal.name}: the solver failed the solvability gate, {gate.summary()}")
                log.warning("task %d: %s; proposing again", index, dropped[-1])
                existing = (*existing, proposal.name)
                dropped_names.add(proposal.name)
                continue
            break
        else:
            raise GeneratorError(f"task {index}: no proposal passed after {MAX_TASK_ATTEMPTS} attempts: "
                                 f"{'; '.join((reasons + dropped)[-3:])}")
        after = render_spec(planned, seed=seed)
        _write(files.record("proposal"), to_json(proposal))
        _write(files.record("scene_candidates"),
               json.dumps([dataclasses.asdict(c) for c in scenes], indent=2) + "\n")
        _write(files.record("critique"), to_json(refine_log))
        _write(files.record("reward_attempts"), json.dumps(
            {"attempts": [dataclasses.asdict(a) for a in rewards.attempts], "probes": rewards.reports},
            indent=2, sort_keys=True) + "\n")
        if gate is not None:
            _write(files.record("solvability"), json.dumps(gate.to_dict(), indent=2, sort_keys=True) + "\n")
        for view, png in before.items():
            _write(files.render(f"before_{view}"), png)
        for view, png in after.items():
            _write(files.render(f"after_{view}"), png)
        info = GenerationInfo(generator_version=generator_version(),
                              backend=author_name(backend), model=backend.model,
                              is_language_model=backend.is_language_model, seed=seed, index=index,
                              instruction=instruction, command=command, dropped=tuple(dropped))
        _write(files.record("generation"), to_json(info))
        if hasattr(source, "assert_consumed"):
            source.assert_consumed()  # a replay must use every recorded exchange
        committed = publish(root, proposal.name, draft, required=files.generated)
        return TaskSummary(committed, tuple(c.score for c in scenes), refine_log.violations_before,
                           refine_log.violations_after, len(refine_log.rounds), time.perf_counter() - t0, attempt + 1,
                           dict(proposal.substitutions), tuple(dropped), gate)
    finally:
        if draft.exists():
            shutil.rmtree(draft, ignore_errors=True)


def _clear_draft(draft: Path, keep: Path) -> None:
    """Remove what an earlier, dropped proposal wrote into ``draft`` (the transcript of every exchange stays)."""
    for p in draft.iterdir():
        if p == keep:
            continue
        if p.is_dir():
            shutil.rmtree(p)
        else:
            p.unlink()


def generate(backend_factory: Callable[[], Backend], root: Path, *, n: int = 1, seed: int = 0,
             instruction: str | None = None, command: str = "", progress: Callable[[TaskSummary], None] | None = None,
             candidates: int = N_CANDIDATES, gate_attempts: int = GATE_ATTEMPTS,
             reading: Reading | None = None, failed: list[str] | None = None,
             gate_workers: int = 1) -> list[TaskSummary]:
    """Generate ``n`` tasks into ``root``; tasks that exist (in ``root`` or the repository) are not proposed again.
    ``reading``: the instruction's reading when the caller has it already (read here otherwise). ``failed``: when
    given, a task slot whose proposals all failed is recorded there (with every reason) and the batch goes on;
    otherwise its :class:`GeneratorError` ends the batch."""
    if instruction is not None and reading is None:
        reading = read_instruction(instruction, asset_dicts())
    root.mkdir(parents=True, exist_ok=True)
    clean_drafts(root)
    out: list[TaskSummary] = []
    existing = _existing_names(root)
    novelty = Novelty(existing_tasks(_task_roots(root))) if instruction is None else None
    dropped_names: set[str] = set()  # a proposal dropped in this batch is not proposed again in it
    for i in range(n):
        try:
            summary = generate_task(backend_factory, root, index=i, seed=seed, instruction=instruction,
                                    command=command, existing=(*existing, *sorted(dropped_names)),
                                    candidates=candidates, reading=reading, gate_attempts=gate_attempts,
                                    novelty=novelty, dropped_names=dropped_names, gate_workers=gate_workers)
        except GeneratorError as exc:
            if failed is None or instruction is not None:
                raise
            log.warning("task %d failed, the batch goes on: %s", i, exc)
            failed.append(str(exc))
            continue
        existing = (*existing, summary.committed.name)
        if novelty is not None:
            spec = summary.committed.spec
            novelty.add(ExistingTask(summary.committed.env_id, spec_signature(spec), spec.instruction))
        out.append(summary)
        if progress is not None:
            progress(summary)
    return out
