"""The generator pipeline: propose -> scene -> render -> critique/refine -> plan -> reward code -> validate -> commit.

Each step is a function of typed records (:mod:`generator.steps`); this module runs them in order for one task at a
time, saves every record in the task's draft folder, and publishes it atomically as a task version at the end
(:func:`gendex_envs.task_version.publish`). Every request and answer is recorded to the version's transcript;
replaying it reproduces the task files byte for byte.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import json
import logging
import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import TYPE_CHECKING

from gendex_envs.spec import dump_task_spec
from gendex_envs.task_version import DRAFTS, TaskLayout, TaskVersion, clean_drafts, new_draft, publish
from generator.backends.base import Backend
from generator.backends.transcript import RecordingBackend
from generator.catalog_view import asset_dicts
from generator.errors import GeneratorError
from generator.instruction import Reading, read_instruction
from generator.novelty import ExistingTask, Novelty, existing_tasks, library_entry
from generator.records import GenerationInfo, to_json
from generator.render import render_spec
from generator.steps.gate import GATE_ATTEMPTS, GateResult, run_gate
from generator.steps.plan import plan_stages
from generator.steps.propose import propose
from generator.steps.refine import refine
from generator.steps.reward import write_rewards
from generator.steps.scene import N_CANDIDATES, write_scene

if TYPE_CHECKING:  # pragma: no cover
    from gendex.fanout import Backend as FanOut

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


@dataclass(frozen=True)
class BuiltTask:
    """A finished, unpublished task version: its folder's files (relative path -> bytes) and its summary's fields.
    Bytes rather than a path, so a worker on another machine can hand it back."""

    name: str
    files: dict[str, bytes]
    fields: dict

    def publish(self, root: Path) -> TaskSummary:
        """Write the files into a draft of ``root`` and publish it as the next version of :attr:`name`."""
        draft = new_draft(root)
        try:
            for rel, data in self.files.items():
                _write(draft / rel, data)
            return TaskSummary(publish(root, self.name, draft, required=TaskLayout(draft).generated), **self.fields)
        finally:
            if draft.exists():
                shutil.rmtree(draft, ignore_errors=True)


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


def task_roots(root: Path) -> list[Path]:
    """The output folder and the repository's task folder: where existing tasks live."""
    from gendex_envs.registry import REPO_TASKS_DIR

    return sorted({Path(root), REPO_TASKS_DIR})


def _existing_names(root: Path) -> tuple[str, ...]:
    names = set()
    for r in task_roots(root):
        if r.is_dir():
            names |= {p.name for p in r.iterdir() if p.is_dir() and not p.name.startswith(".")}
    return tuple(sorted(names))


def generate_task(backend_factory: Callable[[], Backend], root: Path, *, index: int, seed: int,
                  instruction: str | None, command: str, existing: tuple[str, ...] = (),
                  candidates: int = N_CANDIDATES, reading: Reading | None = None,
                  gate_attempts: int = GATE_ATTEMPTS, novelty: Novelty | None = None,
                  dropped_names: set[str] | None = None, gate_workers: int = 1,
                  defer_publish: bool = False) -> TaskSummary | BuiltTask:
    """Generate, validate, gate and commit one task with a fresh ``backend_factory()``, recording every exchange.

    With an ``instruction``: its ``reading`` (read here when not given; :class:`~generator.instruction.
    InstructionError` before anything is written when it asks for what GenDex cannot do). A proposal whose scene
    cannot be refined clean, or whose draft the solver does not solve on ``gate_attempts`` unseen seeds
    (:mod:`generator.steps.gate`; 0 skips the gate), is dropped with its reason and the next one is asked for, told
    what failed; after :data:`MAX_TASK_ATTEMPTS` proposals :class:`GeneratorError` lists every reason.
    ``novelty``: the existing tasks an autonomous proposal may not duplicate (:mod:`generator.novelty`).
    ``dropped_names``: names of proposals dropped so far in the batch (not proposed again); this task's are added.
    ``gate_workers``: processes running the gate's attempts (the same result as one).
    ``defer_publish``: return the finished version folder's files as a :class:`BuiltTask` instead of publishing it
    (a worker of a parallel batch; the batch publishes in task order)."""
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
        fields = dict(candidate_violations=tuple(c.score for c in scenes),
                      violations_before=refine_log.violations_before, violations_after=refine_log.violations_after,
                      refine_rounds=len(refine_log.rounds), seconds=time.perf_counter() - t0,
                      proposals_tried=attempt + 1, substitutions=dict(proposal.substitutions),
                      dropped=tuple(dropped), gate=gate)
        if defer_publish:
            packed = {p.relative_to(draft).as_posix(): p.read_bytes() for p in sorted(draft.rglob("*")) if p.is_file()}
            return BuiltTask(proposal.name, packed, fields)
        return TaskSummary(publish(root, proposal.name, draft, required=files.generated), **fields)
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
             gate_workers: int = 1, tasks_on: FanOut | None = None) -> list[TaskSummary]:
    """Generate ``n`` tasks into ``root``; tasks that exist (in ``root`` or the repository) are not proposed again.
    ``reading``: the instruction's reading when the caller has it already (read here otherwise). ``failed``: when
    given, a task slot whose proposals all failed is recorded there (with every reason) and the batch goes on;
    otherwise its :class:`GeneratorError` ends the batch. ``tasks_on``: a fan-out backend (:mod:`gendex.fanout`)
    that runs the batch's tasks in parallel (:func:`_generate_in_parallel`; ``backend_factory`` must then be
    picklable), with the same committed tasks as one process."""
    if instruction is not None and reading is None:
        reading = read_instruction(instruction, asset_dicts())
    created = not root.exists()
    root.mkdir(parents=True, exist_ok=True)
    clean_drafts(root)
    try:
        return _generate(backend_factory, root, n=n, seed=seed, instruction=instruction, command=command,
                         progress=progress, candidates=candidates, gate_attempts=gate_attempts, reading=reading,
                         failed=failed, gate_workers=gate_workers, tasks_on=tasks_on)
    finally:  # a refusal or a failed batch leaves no empty draft folder (nor an output folder it made)
        for empty in (root / DRAFTS, *((root,) if created else ())):
            with contextlib.suppress(OSError):  # rmdir: only when empty
                empty.rmdir()


def _generate(backend_factory: Callable[[], Backend], root: Path, *, n: int, seed: int, instruction: str | None,
              command: str, progress: Callable[[TaskSummary], None] | None, candidates: int, gate_attempts: int,
              reading: Reading | None, failed: list[str] | None, gate_workers: int,
              tasks_on: FanOut | None) -> list[TaskSummary]:
    if tasks_on is not None and n > 1:
        return _generate_in_parallel(backend_factory, root, n=n, seed=seed, instruction=instruction,
                                     command=command, progress=progress, candidates=candidates,
                                     gate_attempts=gate_attempts, reading=reading, failed=failed, backend=tasks_on)
    out: list[TaskSummary] = []
    existing = _existing_names(root)
    novelty = Novelty(existing_tasks(task_roots(root))) if instruction is None else None
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
            novelty.add(library_entry(summary.committed))
        out.append(summary)
        if progress is not None:
            progress(summary)
    return out


# ---------------------------------------------------------------------------------------------- tasks in parallel
@dataclass(frozen=True)
class BatchState:
    """All a task of a batch takes from the tasks before it: the names it may not propose (existing tasks and
    those committed in the batch), the proposals the batch dropped, and the tasks the batch committed (which the
    near-duplicate test adds to the library's)."""

    names: tuple[str, ...]
    dropped: frozenset[str] = frozenset()
    added: tuple[ExistingTask, ...] = ()

    def existing(self) -> tuple[str, ...]:
        return (*self.names, *sorted(self.dropped))

    def after(self, name: str | None, dropped: frozenset[str], entry: ExistingTask | None) -> BatchState:
        """The state after a task that committed ``name`` (None: its slot failed) and dropped ``dropped``."""
        return BatchState(self.names if name is None else (*self.names, name), self.dropped | dropped,
                          self.added if entry is None else (*self.added, entry))


@dataclass(frozen=True)
class _Outcome:
    index: int
    state: BatchState
    """The state this task was generated from (the batch's guess, checked before its result is used)."""
    built: BuiltTask | None
    error: str | None
    dropped: frozenset[str]


class _TaskWorker:
    """Generates one task of a batch from a given :class:`BatchState`, into a private folder, unpublished."""

    def __init__(self, backend_factory, *, seed, instruction, command, candidates, gate_attempts, reading, library):
        self.kw = dict(seed=seed, instruction=instruction, command=command, candidates=candidates,
                       reading=reading, gate_attempts=gate_attempts)
        self.factory = backend_factory
        self.novelty = Novelty(list(library)) if library is not None else None  # embedded once per worker

    def __call__(self, job: tuple[int, BatchState] | None) -> _Outcome | None:
        if job is None:  # the batch had nothing to submit (see _Submissions)
            return None
        index, state = job
        dropped = set(state.dropped)
        novelty = self.novelty.extended(state.added) if self.novelty is not None else None
        with tempfile.TemporaryDirectory(prefix="gendex-gen-") as root:  # holds the task's draft only
            try:
                built = generate_task(self.factory, Path(root), index=index, existing=state.existing(),
                                      novelty=novelty, dropped_names=dropped, defer_publish=True, **self.kw)
            except GeneratorError as exc:
                return _Outcome(index, state, None, str(exc), frozenset(dropped))
        return _Outcome(index, state, built, None, frozenset(dropped))


def _guess(backend_factory, state: BatchState, index: int, instruction, reading, novelty: Novelty | None
           ) -> BatchState:
    """The state after task ``index`` if its first proposal is committed as proposed: a guess, checked later."""
    from generator.novelty import proposal_assets, proposal_signature

    try:
        proposal, _ = propose(backend_factory(), index=index, existing=state.existing(), instruction=instruction,
                              reading=reading, novelty=novelty.extended(state.added) if novelty else None)
    except GeneratorError:
        return state
    entry = None
    if novelty is not None:
        as_written = dataclasses.asdict(proposal)
        entry = ExistingTask(f"GenDex/{proposal.name}-v0", proposal_signature(as_written), proposal.description,
                             proposal_assets(as_written))
    return state.after(proposal.name, frozenset(), entry)


class _Submissions:
    """The jobs of a parallel batch, pulled lazily by the fan-out: task ``next`` from state ``guess``, each next
    task from the guess that the one before commits its first proposal. :meth:`restart` resubmits from a task with
    the true state. ``None`` is a job that does nothing: there is nothing to submit until a result comes back."""

    def __init__(self, n: int, state: BatchState, guess):
        self.n, self.next, self.guess_state, self._guess = n, 0, state, guess
        self.submitted: dict[int, BatchState] = {}
        """The state each task's latest job was given."""

    def restart(self, index: int, state: BatchState) -> None:
        self.next, self.guess_state = index, state

    def __iter__(self):
        while True:
            i = self.next
            if i >= self.n:
                yield None
                continue
            state = self.guess_state
            self.submitted[i] = state
            # advanced before the yield: a restart made while this job is out must not be overwritten
            self.next, self.guess_state = i + 1, (self._guess(state, i) if i + 1 < self.n else state)
            yield i, state


def _generate_in_parallel(backend_factory, root: Path, *, n: int, seed: int, instruction, command, progress,
                          candidates, gate_attempts, reading, failed, backend: FanOut) -> list[TaskSummary]:
    """Tasks ``0..n-1`` on ``backend``'s workers, committed exactly as :func:`generate` commits them in one process.

    Task i depends on the tasks before it only through a :class:`BatchState`. Each job carries a guess of that state
    (each earlier task commits its first proposal; proposing is cheap next to scenes, renders and the gate, and the
    offline author answers a question the same way every time), and a worker generates the task from it without
    publishing. Results are taken in task order; one is published only when the state it was generated from equals
    the true state (the state after every task before it, as they were actually committed), and the true state
    advances. When a task's outcome differs from its guess (the gate dropped its first proposal, say), the tasks
    after it are submitted again from the true state and the results of the wrong guesses are dropped. Nothing is
    published out of order or from a wrong state, so the committed folders equal a single process's."""
    from gendex.fanout import ordered_map, session

    library = existing_tasks(task_roots(root)) if instruction is None else None
    novelty = Novelty(library) if library is not None else None
    make_worker = functools.partial(_TaskWorker, backend_factory, seed=seed, instruction=instruction,
                                    command=command, candidates=candidates, gate_attempts=gate_attempts,
                                    reading=reading, library=library)
    state = BatchState(_existing_names(root))
    jobs = _Submissions(n, state, lambda s, i: _guess(backend_factory, s, i, instruction, reading, novelty))
    out: list[TaskSummary] = []
    k, redone = 0, 0  # k: the next task slot to publish
    with session(backend):
        stream = ordered_map(make_worker, iter(jobs), backend, ahead=backend.workers)
        try:
            for outcome in stream:
                if outcome is None or outcome.index != k or outcome.state != state:
                    continue  # nothing, a task already published, or a task generated from a wrong guess
                k += 1
                if outcome.built is None:
                    if failed is None or instruction is not None:
                        raise GeneratorError(outcome.error)
                    log.warning("task %d failed, the batch goes on: %s", outcome.index, outcome.error)
                    failed.append(outcome.error)
                    state = state.after(None, outcome.dropped, None)
                else:
                    summary = outcome.built.publish(root)
                    state = state.after(summary.committed.name, outcome.dropped,
                                        library_entry(summary.committed) if novelty is not None else None)
                    out.append(summary)
                    if progress is not None:
                        progress(summary)
                if k == n:
                    break
                if jobs.submitted.get(k, state) != state:  # the next task was generated from a wrong guess
                    log.info("task %d did not commit as guessed; task %d is generated again", k - 1, k)
                    redone += 1
                    jobs.restart(k, state)
                elif k not in jobs.submitted:  # not submitted yet: from the true state rather than a guess
                    jobs.restart(k, state)
        finally:
            stream.close()
    log.info("generated %d task slot(s) on %s; %d guess(es) redone", n, backend.describe(), redone)
    return out
