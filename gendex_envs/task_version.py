"""``TaskVersion``: the one owner of a versioned task folder ``<root>/<Name>/v<N>/``.

A task version is data: its spec, the reward modules that shape it, and what was learned or recorded for it.
:class:`TaskLayout` is the only place in GenDex that spells the folder's file names::

    task.yaml                      the spec (:mod:`gendex_envs.spec`): scene, stages, success conditions
    reward.py                      reward module of the whole task: fail, diagnostics, dense reward, observations
    stage_rewards/<stage>.py       reward module of one stage (optional; a stage without one uses reward.py)
    start_states/<stage>.npz       states a stage env starts from (saved where the previous stage succeeded)
    policies/<stage>.zip           a trained stage policy, run by the stage executor
    policies/<stage>.json          how it was trained (preset, steps, seed, observation normalisation, evaluation)
    policies/<stage>/progress.csv  its training curve (policies/<stage>/checkpoints/ only in training runs)
    renders/<name>.png             scene views (before/after refinement)
    generation.json, proposal.json, scene_candidates.json, critique.json, reward_attempts.json, transcript.jsonl
                                   how the generator made it (replaying the transcript reproduces the files)
    promotion.json                 which version and training runs it was derived from (``gendex promote``)
    reword.json                    which version it rewords, and both wordings (``gendex reword``)

A published version never changes behaviour: a new policy, reward or set of start states is a new version
(:func:`derive_version`; any copy of a version with a change and a record: :func:`publish_derived`). Folders are
published atomically (:func:`publish`): a draft is assembled in the hidden ``<root>/.drafts/`` folder and renamed
into place, so a killed run never leaves a half-written version.

A training run folder (``gendex train --out RUN``) uses the same layout for what it produces (``policies/``,
``start_states/``) plus ``run.json``; :class:`Artifacts` reads policies and start states from either kind of folder.
"""

from __future__ import annotations

import json
import logging
import os
import re
import shutil
import stat
import uuid
from collections.abc import Callable, Collection, Iterable
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING

from gendex_envs.errors import StageError, TaskNotFoundError, TaskSpecError
from gendex_envs.spec import SNAKE_NAME_RE, TASK_NAME_RE, StageSpec, TaskSpec, load_task_spec, resolve_stage

if TYPE_CHECKING:  # pragma: no cover
    from gendex_envs.reward_module import RewardModule
    from gendex_envs.start_states import StartStates
    from gendex_envs.success import Judge

log = logging.getLogger(__name__)

NAMESPACE = "GenDex"
"""Gymnasium namespace of every GenDex task id (``GenDex/<Name>-v<N>``)."""
DRAFTS = ".drafts"
"""Hidden folder of a task root where versions are assembled before they are published (never registered)."""
VERSION_DIR = re.compile(r"\Av(0|[1-9][0-9]{0,8})\Z")
"""A version folder's name: ``v`` and the version in ASCII digits, no leading zero, the whole name (``$`` would match
before a final newline, ``\\d`` any script's digits: ``v1\\n`` and ``v\u0661`` would both be version 1)."""
RECORDS = ("generation", "proposal", "scene_candidates", "critique", "reward_attempts", "solvability", "promotion",
           "reword", "revision", "run")
"""JSON records a folder may hold (how it was generated, promoted, reworded, revised or trained). A ``revision`` is a
change to a published task that a new version carries (its source, what changed and why)."""


class TaskLayout:
    """Paths of every artifact inside one task-version (or training-run) folder; nothing is read or created."""

    def __init__(self, root: str | Path):
        self.root = Path(root)

    def __repr__(self) -> str:
        return f"TaskLayout({str(self.root)!r})"

    @property
    def spec(self) -> Path:
        return self.root / "task.yaml"

    @property
    def reward(self) -> Path:
        """Reward module of the whole task."""
        return self.root / "reward.py"

    @property
    def stage_rewards(self) -> Path:
        """Folder of the per-stage reward modules."""
        return self.root / "stage_rewards"

    def stage_reward(self, stage: str) -> Path:
        return self.stage_rewards / f"{stage}.py"

    @property
    def start_states_dir(self) -> Path:
        return self.root / "start_states"

    def start_states(self, stage: str) -> Path:
        return self.start_states_dir / f"{stage}.npz"

    @property
    def policies(self) -> Path:
        return self.root / "policies"

    def policy(self, stage: str) -> Path:
        """The trained model of ``stage`` (a stable-baselines3 zip)."""
        return self.policies / f"{stage}.zip"

    def policy_record(self, stage: str) -> Path:
        """JSON record beside the model: training settings, observation normalisation, evaluation."""
        return self.policies / f"{stage}.json"

    def policy_curves(self, stage: str) -> Path:
        """Folder of the training curve (``progress.csv``) and of intermediate checkpoints."""
        return self.policies / stage

    def policy_checkpoints(self, stage: str) -> Path:
        """Intermediate models saved while training (kept in run folders, never published)."""
        return self.policy_curves(stage) / "checkpoints"

    @property
    def renders(self) -> Path:
        return self.root / "renders"

    def render(self, name: str) -> Path:
        return self.renders / f"{name}.png"

    def record(self, kind: str) -> Path:
        """``<kind>.json``; ``kind`` is one of :data:`RECORDS`."""
        if kind not in RECORDS:
            raise ValueError(f"unknown record {kind!r}; records: {list(RECORDS)}")
        return self.root / f"{kind}.json"

    @property
    def transcript(self) -> Path:
        """Every request to and answer of the generator's backend, in order (replayable)."""
        return self.root / "transcript.jsonl"

    @property
    def generated(self) -> tuple[Path, ...]:
        """Files every generated task folder holds when it is committed."""
        return (self.spec, self.reward, self.record("proposal"), self.record("generation"), self.transcript)

    def reward_modules(self) -> list[Path]:
        """The reward modules present: ``reward.py`` first, then the stage modules by name."""
        found = [self.reward] if self.reward.is_file() else []
        if self.stage_rewards.is_dir():
            found += sorted(self.stage_rewards.glob("*.py"))
        return found

    def module_stage(self, path: str | Path) -> str | None:
        """The stage whose reward module ``path`` is; None for the task's module (or a file elsewhere)."""
        p = Path(path).resolve()
        return p.stem if p.parent == self.stage_rewards.resolve() and p.suffix == ".py" else None

    def resolve(self, path: str | Path) -> Path:
        """Where ``path`` (one of this layout's paths) is to be read: the folder's own file when present, else the
        store object that ``tree.json`` lists for it (:mod:`gendex_envs.task_store`). The other paths of a layout are
        where files are written and never lead into the shared store."""
        from gendex_envs.task_store import resolve

        path = Path(path)
        try:
            rel = path.relative_to(self.root).as_posix()
        except ValueError:
            return path
        return resolve(self.root, rel)

    def stored(self, sub: str, suffix: str) -> dict[str, Path]:
        """Files ``<sub>/<stem><suffix>`` of the folder, its own and stored ones: stem -> where to read it."""
        from gendex_envs.task_store import listing

        return listing(self.root, sub, suffix)

    def relative(self, path: str | Path) -> str:
        """``path`` relative to the folder (as shown in messages), or unchanged when it lies elsewhere."""
        try:
            return Path(path).resolve().relative_to(self.root.resolve()).as_posix()
        except ValueError:
            return str(path)


@dataclass(frozen=True)
class PolicyFiles:
    """A trained stage policy: the model and its JSON record."""

    stage: str
    model: Path
    record: Path
    shown: Path | None = field(default=None, compare=False)
    """The model's path in its version folder, to show and record, when ``model`` lies in the task store; None: the
    model's own path."""

    @property
    def where(self) -> Path:
        return self.shown if self.shown is not None else self.model

    def meta(self) -> dict:
        return json.loads(self.record.read_text())


class Artifacts:
    """Trained policies and start states of a folder laid out as :class:`TaskLayout` (a version or a run)."""

    def __init__(self, root: str | Path):
        self.layout = TaskLayout(root)

    def __repr__(self) -> str:
        return f"Artifacts({str(self.layout.root)!r})"

    def policy(self, stage: str) -> PolicyFiles | None:
        """The policy of ``stage`` when both its model and record exist, else None."""
        model = self.layout.resolve(self.layout.policy(stage))
        record = self.layout.resolve(self.layout.policy_record(stage))
        if not (model.is_file() and record.is_file()):
            return None
        named = self.layout.policy(stage)
        return PolicyFiles(stage, model, record, named if named != model else None)

    def policy_stages(self) -> list[str]:
        """Stages with a complete trained policy here."""
        return [s for s in self.layout.stored("policies", ".zip") if self.policy(s) is not None]

    def start_states(self, stage: str) -> StartStates | None:
        from gendex_envs.start_states import StartStates

        path = self.layout.resolve(self.layout.start_states(stage))
        return StartStates.load(path) if path.is_file() else None

    def start_state_stages(self) -> list[str]:
        return list(self.layout.stored("start_states", ".npz"))


@dataclass(frozen=True)
class TaskVersion:
    """One published version of a task: ``<root>/<name>/v<version>/`` (see the module docstring).

    Build with :meth:`at`. Everything is read on demand and cached: the spec (checked against the asset catalog),
    reward modules, success judges.
    """

    root: Path
    """The version folder."""
    name: str
    version: int

    @classmethod
    def at(cls, folder: str | Path) -> TaskVersion:
        """The version in ``folder`` (``.../<Name>/v<N>`` holding a spec); :class:`TaskNotFoundError` otherwise."""
        folder = Path(folder)
        m = VERSION_DIR.fullmatch(folder.name)
        if m is None:
            raise TaskNotFoundError(f"{folder} is not a task version folder: version folders are named v<N> inside "
                                    "a folder named after the task (e.g. generated_tasks/PutAppleBowl/v0)")
        if not TaskLayout(folder).spec.is_file():
            raise TaskNotFoundError(f"{folder} holds no task spec ({TaskLayout(folder).spec.name})")
        return cls(root=folder, name=folder.parent.name, version=int(m.group(1)))

    def __getstate__(self) -> dict:
        # only the identity travels to worker processes; caches (loaded reward modules) are rebuilt there
        return {"root": self.root, "name": self.name, "version": self.version}

    # ------------------------------------------------------------------ identity
    @property
    def env_id(self) -> str:
        return f"{NAMESPACE}/{self.name}-v{self.version}"

    @property
    def files(self) -> TaskLayout:
        return TaskLayout(self.root)

    @property
    def artifacts(self) -> Artifacts:
        return Artifacts(self.root)

    @property
    def tasks_root(self) -> Path:
        """The folder holding ``<Name>/`` (e.g. ``generated_tasks/``)."""
        return self.root.parent.parent

    # ------------------------------------------------------------------ spec
    @cached_property
    def spec(self) -> TaskSpec:
        """The spec, validated against the asset catalog; :class:`TaskSpecError` naming the file otherwise."""
        from gendex_envs.assets.catalog import asset_ids

        spec = load_task_spec(self.files.spec, known_assets=asset_ids())
        self._check_name(spec)
        return spec

    def load_spec_unchecked(self) -> TaskSpec:
        """The spec without the asset-catalog check (cheap: what registration needs)."""
        spec = load_task_spec(self.files.spec)
        self._check_name(spec)
        return spec

    def _check_name(self, spec: TaskSpec) -> None:
        if spec.name != self.name:
            raise TaskSpecError(f"{self.files.spec}: name {spec.name!r} differs from its folder {self.name!r}; the "
                                "folder name is the task's id, so they must agree")

    def stage(self, stage: str | int) -> tuple[int, StageSpec]:
        """(index, spec) of a stage given by name or index; :class:`StageError` naming the stages otherwise."""
        return resolve_stage(self.spec, stage)

    # ------------------------------------------------------------------ reward modules and success
    def has_stage_reward(self, stage: str) -> bool:
        return self.files.stage_reward(stage).is_file()

    def reward_path(self, stage: str | None = None) -> Path:
        """Module of ``stage``: its own when the version has one, else the task's."""
        if stage is not None and self.has_stage_reward(stage):
            return self.files.stage_reward(stage)
        return self.files.reward

    def reward(self, stage: str | None = None) -> RewardModule:
        """The reward module of ``stage`` (or of the task), loaded once: a published version never changes."""
        from gendex_envs.reward_module import load_reward_module

        path = self.reward_path(stage)
        cache = self.__dict__.setdefault("_rewards", {})
        if path not in cache:
            cache[path] = load_reward_module(path)
        return cache[path]

    def judge(self, stage: str | int | None = None) -> Judge:
        """What decides success of the whole task (``stage`` None) or of one stage; see :mod:`gendex_envs.success`."""
        from gendex_envs.success import Judge

        if stage is None:
            return Judge.of_task(self.spec, self.reward())
        _, st = self.stage(stage)
        return Judge.of_stage(self.spec, st, self.reward(st.name))

    def copy_to(self, folder: str | Path, skip: tuple[str, ...] = ("__pycache__",)) -> Path:
        """Write this whole version as a plain folder (``<root>/<Name>/v<N>`` of another task root): its stored files
        (:mod:`gendex_envs.task_store`) are copied out of the store, so the copy needs none."""
        from gendex_envs.task_store import export

        return export(self.root, folder, skip)

    # ------------------------------------------------------------------ learned and recorded artifacts
    def policy(self, stage: str) -> PolicyFiles | None:
        return self.artifacts.policy(stage)

    def start_states(self, stage: str) -> StartStates | None:
        return self.artifacts.start_states(stage)

    def renders(self) -> dict[str, Path]:
        """Rendered views by name (e.g. ``after_top_down``)."""
        return self.files.stored("renders", ".png")

    def provenance(self) -> dict[str, dict]:
        """The JSON records present (generation, proposal, critique, promotion, ...), by kind."""
        out = {}
        for kind in RECORDS:
            path = self.files.resolve(self.files.record(kind))
            if path.is_file():
                out[kind] = json.loads(path.read_text())
        return out

    def file_digest(self) -> str:
        """SHA-256 over every file's relative path and bytes: equal digests mean an unchanged version. It covers
        everything in the whole version (spec, reward and stage reward modules, policies and their records, start
        states, any other file, hidden ones included; a stored file, :mod:`gendex_envs.task_store`, counts by its path
        in the version and its bytes, checked against its name, so a packed version digests as the whole folder it was
        packed from), so any change that could alter behaviour changes it; left out are ``tree.json``, the
        ``solvability`` record, a measurement of the version (``gendex gate --write`` may add or renew it), not part
        of it, and ``__pycache__`` folders: nothing reads them (reward modules are compiled from their checked text,
        :func:`~gendex_envs.reward_module.load_reward_module`), and ``pip install`` of the wheel writes them beside
        every shipped ``.py`` file, so an installed library digests as the checkout does.

        Stable across checkouts and machines: files are taken in the order of their relative paths (by parts), and only
        their bytes count (not times, modes or owners). Files are read in chunks; a symbolic link counts as its
        target's text (it is never followed, so a link to a device or a huge file outside costs nothing), and any
        other non-regular entry (a FIFO, a socket) counts as its kind, without being opened."""
        import hashlib
        import stat

        from gendex_envs.task_store import files, read_object

        h = hashlib.sha256()
        skip = self.files.record("solvability").relative_to(self.root).as_posix()
        for rel, path, sha in files(self.root):
            if rel == skip:
                continue
            h.update(rel.encode("utf-8", "surrogateescape") + b"\0")
            if sha is not None:  # a stored file: its bytes, checked against the object's name
                h.update(read_object(path, sha))
                continue
            mode = path.lstat().st_mode
            if stat.S_ISLNK(mode):
                h.update(b"\0symlink\0" + os.fsencode(os.readlink(path)))
            elif stat.S_ISREG(mode):
                with path.open("rb") as fh:
                    for chunk in iter(lambda: fh.read(1 << 20), b""):
                        h.update(chunk)
            else:
                h.update(b"\0special\0" + str(stat.S_IFMT(mode)).encode())
        return h.hexdigest()


# ---------------------------------------------------------------------------------------- task roots
def versions_in(root: str | Path) -> list[TaskVersion]:
    """Every version folder under ``root`` (``<root>/<Name>/v<N>/`` holding a spec), sorted by name and version.

    Folders that look like versions but are not (no spec, a lower-case name) are logged and skipped."""
    root = Path(root)
    found = []
    for spec in sorted(root.glob("*/v*/" + TaskLayout(".").spec.name)):
        folder = spec.parent
        if not VERSION_DIR.fullmatch(folder.name) or not TASK_NAME_RE.fullmatch(folder.parent.name):
            log.warning("ignoring %s (%r): a task version folder is <Name>/v<N>, an ASCII CamelCase name and v with "
                        "the version in ASCII digits", folder, folder.relative_to(root).as_posix())
            continue
        try:
            found.append(TaskVersion.at(folder))
        except TaskNotFoundError as exc:  # task.yaml is a folder, a FIFO, a dangling link: skip only this one
            log.warning("ignoring %s: %s", folder, exc)
    return sorted(found, key=lambda v: (v.name, v.version))


def next_version(root: str | Path, name: str) -> int:
    folder = Path(root) / name
    if not folder.is_dir():
        return 0
    numbers = [int(m.group(1)) for p in folder.iterdir() if (m := VERSION_DIR.fullmatch(p.name))]
    return max(numbers) + 1 if numbers else 0


def new_draft(root: str | Path) -> Path:
    """A fresh, empty draft folder in ``<root>/.drafts/``."""
    d = Path(root) / DRAFTS / uuid.uuid4().hex[:12]
    d.mkdir(parents=True)
    return d


def clean_drafts(root: str | Path) -> int:
    """Remove drafts left behind by killed runs; returns how many."""
    drafts = Path(root) / DRAFTS
    if not drafts.is_dir():
        return 0
    stale = list(drafts.iterdir())
    for p in stale:
        shutil.rmtree(p, ignore_errors=True)
    if stale:
        log.info("removed %d unfinished draft(s) from %s", len(stale), drafts)
    return len(stale)


class PublishError(TaskSpecError):
    """A draft cannot be published as a task version (incomplete, or no free version folder)."""


def publish(root: str | Path, name: str, draft: Path, required: Iterable[Path] = ()) -> TaskVersion:
    """Publish ``draft`` (a complete version folder) as ``<root>/<name>/v<N>`` with the next free N.

    One ``rename`` makes it appear: the whole ``<name>`` folder when the task is new, else the version folder inside
    it. ``required``: files (inside ``draft``) that must exist; :class:`PublishError` otherwise, nothing published.
    In a root with a store (``<root>/.objects``, :mod:`gendex_envs.task_store`) the draft is packed first; a root
    with a registration index (:mod:`gendex_envs.task_index`) records the new version in it.
    """
    root = Path(root)
    if not TASK_NAME_RE.fullmatch(name):
        raise PublishError(f"task name {name!r} is not CamelCase (ASCII, [A-Z][A-Za-z0-9]*)")
    missing = [p.name for p in required if not p.is_file()]
    if missing:
        raise PublishError(f"task {name!r} is incomplete, not publishing it: missing {missing}")
    from gendex_envs.task_store import OBJECTS, pack

    if (root / OBJECTS).is_dir():  # a root with a store keeps its versions packed
        pack(draft)
    for _ in range(100):
        version = next_version(root, name)
        wrapper = draft.parent / f"{draft.name}-publish"
        target_parent = root / name
        try:
            if not target_parent.exists():
                (wrapper / f"v{version}").parent.mkdir(parents=True, exist_ok=True)
                os.rename(draft, wrapper / f"v{version}")
                try:
                    os.rename(wrapper, target_parent)  # the whole <name> folder appears at once
                except OSError:
                    os.rename(wrapper / f"v{version}", draft)  # another run created <name>: retry inside it
                    shutil.rmtree(wrapper, ignore_errors=True)
                    continue
            else:
                os.rename(draft, target_parent / f"v{version}")
        except FileExistsError:
            continue
        except OSError as exc:
            if (target_parent / f"v{version}").exists():
                continue
            raise PublishError(f"could not publish task {name!r} into {root}: {exc}") from exc
        log.info("published %s", target_parent / f"v{version}")
        published = TaskVersion.at(target_parent / f"v{version}")
        from gendex_envs.task_index import add_to_index

        add_to_index(published)
        return published
    raise PublishError(f"could not find a free version folder for {name!r} in {root}")


def publish_derived(source: TaskVersion, kind: str, edit: Callable[[TaskLayout], dict],
                    skip: tuple[str, ...] = ("__pycache__",)) -> TaskVersion:
    """Publish ``v<N+1>`` of ``source``'s task: a copy of ``source`` (without files matching ``skip``) that
    ``edit`` changes in the draft, with the record ``edit`` returns (and the source's id) saved as ``kind``. Nothing
    is published when ``edit`` raises; ``source`` is left untouched."""
    from gendex_envs.atomic_io import write_json

    root = source.tasks_root
    draft = new_draft(root)
    try:
        shutil.copytree(source.root, draft, dirs_exist_ok=True, ignore=shutil.ignore_patterns(*skip))
        out = TaskLayout(draft)
        record = edit(out)
        write_json(out.record(kind), dict(record, source=source.env_id), indent=2, sort_keys=True)
        return publish(root, source.name, draft, required=(out.spec, out.reward))
    finally:
        if draft.exists():
            shutil.rmtree(draft, ignore_errors=True)


MAX_PROMOTED_FILE_BYTES = 600_000_000
"""Largest file ``gendex promote`` copies out of a run (a policy zip of the paper's network is about 30 MB; the
policy loader's own bound on its weights is 256 MB)."""


def _run_file(root: Path, path: Path) -> Path:
    """``path`` (under the run folder ``root``), checked before it is copied into a task version: a regular file,
    no symbolic link on the way from ``root`` (a link would copy a file from anywhere, ``~/.ssh/id_rsa`` or
    ``/dev/zero``, into the task folder), at most :data:`MAX_PROMOTED_FILE_BYTES`. :class:`StageError` otherwise."""
    rel = path.relative_to(root)
    at = root
    for part in rel.parts:
        at = at / part
        try:
            mode = os.lstat(at).st_mode
        except OSError as exc:
            raise StageError(f"cannot promote {path}: {exc.strerror}") from None
        if stat.S_ISLNK(mode):
            raise StageError(f"cannot promote {path}: {at} is a symbolic link; a run's policies and start states "
                             "must be regular files inside it")
    size = os.lstat(path)
    if not stat.S_ISREG(size.st_mode):
        raise StageError(f"cannot promote {path}: not a regular file")
    if size.st_size > MAX_PROMOTED_FILE_BYTES:
        raise StageError(f"cannot promote {path}: {size.st_size} bytes; at most MAX_PROMOTED_FILE_BYTES = "
                         f"{MAX_PROMOTED_FILE_BYTES} are allowed")
    return path


def _copy_run_file(root: Path, src: Path, dst: Path) -> None:
    """Copy ``src`` (checked by :func:`_run_file`) to ``dst``, opened without following a link (a link put there
    after the check is refused too)."""
    _run_file(root, src)
    fd = os.open(src, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
    with os.fdopen(fd, "rb") as f, open(dst, "wb") as out:
        shutil.copyfileobj(f, out)
    shutil.copystat(src, dst, follow_symlinks=False)


def derive_version(source: TaskVersion, overlays: Collection[Artifacts], record: dict) -> TaskVersion:
    """Publish ``v<N+1>`` of ``source``'s task: a copy of ``source`` with the policies and start states of
    ``overlays`` (later overlays win) and ``record`` saved as ``promotion.json``. ``source`` is left untouched.

    A run folder is untrusted data (``gendex promote`` may be given any folder): every file copied must be a regular
    file reached through no symbolic link and within :data:`MAX_PROMOTED_FILE_BYTES`, stage names must be snake_case
    names, and start states must load (:meth:`StartStates.load <gendex_envs.start_states.StartStates.load>`:
    bounded, finite). A refusal is a :class:`StageError` and publishes nothing."""
    from gendex_envs.start_states import StartStates

    def stage_name(art: Artifacts, stage: str) -> str:
        if not SNAKE_NAME_RE.fullmatch(stage):
            raise StageError(f"cannot promote {art.layout.root}: stage {stage[:100]!r} is not a snake_case stage name")
        return stage

    def overlay(out: TaskLayout) -> dict:
        copied: dict[str, list[str]] = {"policies": [], "start_states": []}
        for art in overlays:
            src = art.layout
            root = src.root
            for stage in art.policy_stages():
                stage_name(art, stage)
                out.policies.mkdir(parents=True, exist_ok=True)
                _copy_run_file(root, src.policy(stage), out.policy(stage))
                _copy_run_file(root, src.policy_record(stage), out.policy_record(stage))
                curve = src.policy_curves(stage) / "progress.csv"
                if curve.is_file() or curve.is_symlink():
                    out.policy_curves(stage).mkdir(parents=True, exist_ok=True)
                    _copy_run_file(root, curve, out.policy_curves(stage) / curve.name)
                copied["policies"].append(stage)
            for stage in art.start_state_stages():
                stage_name(art, stage)
                StartStates.load(_run_file(root, src.start_states(stage)))  # bounded and finite, or StageError
                out.start_states_dir.mkdir(parents=True, exist_ok=True)
                _copy_run_file(root, src.start_states(stage), out.start_states(stage))
                copied["start_states"].append(stage)
        if not any(copied.values()):
            raise StageError(f"nothing to promote: {', '.join(str(a.layout.root) for a in overlays)} hold no "
                             "trained policy or start states")
        return dict(record, **copied)

    return publish_derived(source, "promotion", overlay, skip=("checkpoints", "__pycache__"))
