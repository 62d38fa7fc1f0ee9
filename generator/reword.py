"""Wording a library that reads as varied as its tasks: the least-alike framing of each task's command.

The offline author frames each command with an optional situation before it and purpose after it
(:func:`generator.phrasing.framings`). Drawn at random, the same few situations come back across a library and its
instructions read alike (86 tasks measured a mean pairwise all-MiniLM-L6-v2 cosine of 0.299, against 0.191 for
RoboGen). Here the framing is *chosen*: the one whose embedding is least like the library's other instructions
(lowest mean cosine). The command, the only part that says what success needs, changes only to another wording the
instruction reader reads as the very same task (:mod:`generator.command_wording`; :func:`plan_commands`, ``gendex
reword --commands``, and every proposal of the offline author): the library's commands alone measured 0.333 with one
template each.

- :class:`LibraryWording` picks for one new task against a fixed library (the offline author's proposals);
- :func:`plan_rewording` picks for every task of a library at once, each against all the others, a few passes
  round until nothing changes (coordinate descent on the library's mean pairwise cosine);
- :func:`publish_reworded` publishes the new wording as the task's next version (a published version never
  changes): the folder copied, the ``instruction`` entry of the spec replaced and nothing else, and a ``reword``
  record naming the source version and both wordings. The solvability record is copied with it: the scene,
  stages and reward are byte-identical to those the gate ran on.
"""

from __future__ import annotations

import logging
import re
from collections import Counter
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np
import yaml

from gendex_envs.spec import TaskSpec
from gendex_envs.task_version import TaskLayout, TaskVersion, publish_derived
from generator.catalog_view import asset_dict
from generator.embedding import embed, embed_each, mean_pairwise_cosine
from generator.phrasing import SURFACES, Frame, direction, domain, framings, split
from generator.stats import latest_versions, task_skills

log = logging.getLogger(__name__)

RIGID_CONDITIONS = ("lifted", "inside", "over", "near", "rotated", "placed", "wiped", "hung", "poured",
                    "flipped")
"""Success conditions whose ``object`` is the object a rigid part of the task moves."""
MAX_REUSE = 2
"""A situation or purpose frames at most this many of the reworded library's instructions (the embedding alone
would frame six tasks with the one sentence least like the rest)."""
MAX_PAIR_COSINE = 0.85
"""No framing is chosen that reads this much like another instruction of the library, where one that does not
exists: a low mean alone lets two sibling tasks (the left- and the right-hinged fridge) take the same frame and read
as one (:data:`generator.novelty.NEAR_DUPLICATE_COSINE` is 0.9)."""
PASSES = 4
"""Most passes of :func:`plan_rewording` over the library (it stops early when a pass changes nothing)."""


class RewordError(ValueError):
    """A task cannot be reworded (its instruction has no command left, or the spec has no such entry)."""


class LibraryWording:
    """Chooses, of the sentences offered, the one least like a fixed set of instructions (lowest mean
    all-MiniLM-L6-v2 cosine). The library's instructions are embedded each on its own and remembered
    (:func:`generator.embedding.embed_each`): a library that grows by one task costs one new embedding, not the whole
    library's again. The sentences offered (a proposal's framings, dozens, each asked once) are embedded in one
    call: one by one they cost ~10x the CPU on a machine that has not seen them, as on every fresh CI machine.
    ImportError when the ``stats`` extra is missing."""

    def __init__(self, instructions: Iterable[str]):
        texts = list(instructions)
        self._emb = embed_each(texts)[0] if texts else None

    def __call__(self, candidates: list[str]) -> str:
        return candidates[0] if len(candidates) == 1 else self.scored(candidates)[0]

    def scored(self, candidates: list[str]) -> tuple[str, float]:
        """The candidate least like the instructions and its mean cosine to them (infinite when it reads like one
        of them: a cosine of :data:`MAX_PAIR_COSINE` or more; 0.0 against no instructions)."""
        if not candidates:
            raise ValueError("no sentences to choose from")
        if self._emb is None:
            return candidates[0], 0.0
        sims = embed(candidates)[0] @ self._emb.T
        best = _least_alike(sims, np.arange(len(candidates)))
        return candidates[best], float(sims[best].mean()) if sims[best].max() < MAX_PAIR_COSINE else float("inf")


def _least_alike(sims: np.ndarray, allowed: np.ndarray) -> int:
    """Of the ``allowed`` rows of ``sims`` (candidates x other instructions), the one with the lowest mean
    cosine among those that read like no other instruction (every cosine below :data:`MAX_PAIR_COSINE`); when
    none is that far from all, the one nearest to it (lowest largest cosine)."""
    rows = sims[allowed]
    apart = rows.max(axis=1) < MAX_PAIR_COSINE if rows.shape[1] else np.ones(len(rows), bool)
    if apart.any():
        means = np.where(apart, rows.mean(axis=1) if rows.shape[1] else 0.0, np.inf)
        return int(allowed[int(np.argmin(means))])
    return int(allowed[int(np.argmin(rows.max(axis=1)))])


def _frames(name: str, skills: Iterable[str], assets: Mapping[str, dict], moved: Iterable[str]) -> tuple[Frame, Frame]:
    art_skill = next((k for k in skills if direction(k)), None)
    art = next((a for a in assets.values() if a.get("joints")), None)
    obj = next((assets[m] for m in moved if m in assets), None)
    art_frame = Frame(domain(art), direction(art_skill)) if art is not None and art_skill else None
    rigid_frame = Frame(domain(obj)) if obj is not None else None
    first, last = art_frame or rigid_frame, rigid_frame or art_frame
    if first is None or last is None:
        raise RewordError(f"{name}: no object the task acts on to frame its instruction by")
    return first, last


def spec_frames(spec: TaskSpec) -> tuple[Frame, Frame]:
    """The frames (:class:`generator.phrasing.Frame`) of the first and the last part of ``spec``: an articulated
    part (open, close, turn) comes first in every composed task the author writes, a rigid one last."""
    assets = {o.name: asset_dict(o.asset) for o in spec.objects if not o.distractor}
    moved = [c.object for c in spec.success.conditions if c.type in RIGID_CONDITIONS]
    return _frames(spec.name, task_skills(spec), assets, moved)


def proposal_frames(proposal: dict) -> tuple[Frame, Frame]:
    """:func:`spec_frames` of a proposal as the offline author writes it (before there is a spec)."""
    from generator.novelty import proposal_signature

    assets = {o["name"]: asset_dict(o["asset"]) for o in proposal["objects"] if o.get("role") != "distractor"}
    moved = [c.get("object") for c in (proposal["success"], *(proposal.get("also") or ()))
             if c.get("type") in RIGID_CONDITIONS]
    return _frames(proposal["name"], proposal_signature(proposal)[0], assets, moved)


class ProposalWording:
    """The offline author's wording of a proposal: the framing of its command least like the library's
    instructions (:class:`LibraryWording`, built once per library); the proposal's drawn wording when the
    ``stats`` extra is not installed."""

    def __init__(self):
        self._library: tuple[tuple[str, ...], LibraryWording | None, LibraryWording | None, Counter] | None = None

    def __call__(self, proposal: dict, library: Iterable[str]) -> dict:
        """``proposal`` worded least like ``library`` (unchanged for an empty library)."""
        return self._worded(proposal, tuple(library))[0]

    def least_alike(self, proposals: list[dict], library: Iterable[str]) -> dict:
        """Of ``proposals`` (a few the author drew of one skill), each worded least like ``library``, the one whose
        command reads least like the library's commands: a library grows towards what it does not say yet (on a
        tie, as without the ``stats`` extra, the first)."""
        if not proposals:
            raise ValueError("no proposals to choose from")
        key = tuple(library)
        worded = [self._worded(p, key) for p in proposals]
        return min(worded, key=lambda w: w[1])[0]

    def _worded(self, proposal: dict, key: tuple[str, ...]) -> tuple[dict, float]:
        if not key:
            return proposal, 0.0
        if self._library is None or self._library[0] != key:
            try:
                used = Counter(x for t in key for x in split(t)[0::2] if x is not None)
                self._library = (key, LibraryWording(key), LibraryWording(split(t)[1] for t in key), used)
            except ImportError as exc:
                log.info("wording drawn at random: %s is not installed (the optional 'stats' extra)", exc.name)
                self._library = (key, None, None, Counter())
        _, choose, choose_command, used = self._library
        if choose is None:
            return proposal, 0.0
        try:
            frames = proposal_frames(proposal)
            command = split(proposal["description"])[1]
            worded, score = choose_command.scored(_command_wordings(command))
            options = candidates_for(proposal["name"], proposal["description"], frames, command=worded)
        except RewordError as exc:
            log.info("kept the drawn wording: %s", exc)
            return proposal, float("inf")
        fresh = [o for o in options if all(x is None or used[x] < MAX_REUSE for x in split(o)[0::2])]
        # no frame the library uses MAX_REUSE times
        return dict(proposal, description=choose(fresh or options)), score


PROPOSAL_WORDINGS = 60
"""Most wordings of a proposal's command read (:func:`generator.command_wording.wordings`); the library's rewording
reads up to :data:`generator.command_wording.MAX_WORDINGS`."""


def _command_wordings(command: str) -> list[str]:
    from generator.catalog_view import asset_dicts
    from generator.command_wording import wordings

    return wordings(command, asset_dicts(), limit=PROPOSAL_WORDINGS)


def _surface(command: str) -> str:
    words = re.findall(r"[a-z]+", command.lower())
    return next((s for s in sorted(SURFACES, key=len, reverse=True) if s in words), SURFACES[0])


def candidates_for(name: str, instruction: str, frames: tuple[Frame, Frame], command: str | None = None) -> list[str]:
    """Every framing (:func:`generator.phrasing.framings`) of the command of ``instruction`` (the instruction with
    its situation and purpose taken off); ``instruction`` itself is always one of them. With ``command`` (another
    wording of that command: :mod:`generator.command_wording`), the framings of ``command`` instead."""
    own = split(instruction)[1]
    if not own.strip():
        raise RewordError(f"{name}: its instruction {instruction!r} has no command")
    if command is not None and command != own:
        return framings(command, *frames, _surface(command))
    out = framings(own, *frames, _surface(own))
    return out if instruction in out else [instruction, *out]


@dataclass(frozen=True)
class Rewording:
    env_id: str
    old: str
    new: str


def _descend(emb: np.ndarray, starts: np.ndarray, choice: list[int], allowed_for=None) -> None:
    """Coordinate descent on the mean pairwise cosine of the chosen rows of ``emb`` (options of task ``i`` are rows
    ``starts[i]:starts[i+1]``), in ``choice``: each task in turn takes its least-alike option (:func:`_least_alike`)
    among those ``allowed_for(i)`` permits, a few passes round until none changes."""
    n = len(choice)
    for _ in range(PASSES):
        changed = 0
        for i in range(n):
            if starts[i + 1] - starts[i] == 1:
                continue
            allowed = allowed_for(i) if allowed_for is not None else np.arange(starts[i], starts[i + 1])
            others = emb[[choice[j] for j in range(n) if j != i]]
            best = int(allowed[_least_alike(emb[allowed] @ others.T, np.arange(len(allowed)))])
            if best != choice[i]:
                choice[i], changed = best, changed + 1
        if not changed:
            return


def plan_commands(commands: list[str], fixed: list[bool], limit: int | None = None) -> list[str]:
    """The wording of each of ``commands`` (bare commands of a library, one per task) least like the others: of
    the wordings the reader reads as that command (:func:`generator.command_wording.wordings`), chosen by
    coordinate descent on the commands' mean pairwise cosine; a ``fixed`` command keeps its words. ``limit``: the
    most wordings read per command (default :data:`generator.command_wording.MAX_WORDINGS`)."""
    from tqdm import tqdm

    from generator.catalog_view import asset_dicts
    from generator.command_wording import MAX_WORDINGS, wordings

    assets = asset_dicts()
    options = [[c] if f else wordings(c, assets, limit=limit or MAX_WORDINGS)
               for c, f in tqdm(list(zip(commands, fixed, strict=True)), desc="wordings read", unit="task",
                                disable=len(commands) < 50)]
    flat = [t for opts in options for t in opts]
    emb = embed(flat)[0]
    starts = np.cumsum([0] + [len(o) for o in options])
    choice = [int(starts[i]) for i in range(len(options))]  # each command's own words come first
    _descend(emb, starts, choice)
    return [flat[k] for k in choice]


def plan_rewording(versions: Mapping[str, TaskVersion], keep: Iterable[str] = (), commands: bool = False,
                   limit: int | None = None) -> tuple[list[Rewording], dict]:
    """New instructions for the latest version of each task in ``versions`` (task names in ``keep`` keep
    theirs), chosen to lower the library's mean pairwise cosine; and the numbers before and after.

    With ``commands`` the command itself is first worded least like the library's other commands
    (:func:`plan_commands`: only wordings the reader reads as the same task); without, it is kept and only its
    framing chosen (``limit``: see :func:`plan_commands`). Returns only the tasks whose wording changes."""
    latest = sorted(latest_versions(versions).items())
    keep = set(keep)
    ids = [env_id for env_id, _ in latest]
    current = [v.spec.instruction for _, v in latest]
    fixed = [v.name in keep for _, v in latest]
    old_commands = [split(t)[1] for t in current]
    new_commands = plan_commands(old_commands, fixed, limit) if commands else old_commands
    options: list[list[str]] = []
    for (_, v), text, cmd, f in zip(latest, current, new_commands, fixed, strict=True):
        options.append([text] if f else candidates_for(v.name, text, spec_frames(v.spec), command=cmd))
    flat = [t for opts in options for t in opts]
    emb = embed(flat)[0]
    starts = np.cumsum([0] + [len(o) for o in options])
    frames = [split(t)[0::2] for t in flat]  # (situation, purpose) of every option
    # each task starts from its own framing (its own instruction, or the new command framed as it was; else bare)
    own = [tuple(split(t)[0::2]) for t in current]
    choice = [int(starts[i] + next((k for k, f in enumerate(frames[starts[i]:starts[i + 1]]) if f == own[i]), 0))
              for i in range(len(options))]
    before = mean_pairwise_cosine(embed(current)[0])
    commands_before = mean_pairwise_cosine(embed(old_commands)[0])
    n = len(choice)

    def allowed_for(i: int) -> np.ndarray:
        used = Counter(x for j in range(n) if j != i for x in frames[choice[j]] if x is not None)
        return np.array([k for k in range(starts[i], starts[i + 1])
                         if all(x is None or used[x] < MAX_REUSE for x in frames[k])])

    _descend(emb, starts, choice, allowed_for)
    out = [Rewording(ids[i], current[i], flat[choice[i]]) for i in range(n) if flat[choice[i]] != current[i]]
    commands_after = mean_pairwise_cosine(embed([split(flat[k])[1] for k in choice])[0])
    return out, {"tasks": n, "kept": sorted(keep & {v.name for _, v in latest}), "reworded": len(out),
                 "mean_pairwise_cosine_before": before, "mean_pairwise_cosine_after": mean_pairwise_cosine(emb[choice]),
                 "commands_mean_pairwise_cosine_before": commands_before,
                 "commands_mean_pairwise_cosine_after": commands_after,
                 "commands_reworded": sum(a != b for a, b in zip(old_commands, new_commands, strict=True))}


def replace_instruction(text: str, instruction: str) -> str:
    """``text`` (a task spec's YAML) with its top-level ``instruction`` value replaced and every other byte kept
    (a header comment that repeats the old instruction is updated with it)."""
    root = yaml.compose(text)
    node = next((v for k, v in root.value if k.value == "instruction"), None) if isinstance(root, yaml.MappingNode) \
        else None
    if node is None:
        raise RewordError("the spec has no top-level 'instruction' entry")
    old = yaml.safe_load(text)["instruction"]
    value = yaml.safe_dump(instruction, width=10_000, allow_unicode=True).removesuffix("...\n").rstrip("\n")
    out = text[:node.start_mark.index] + value + text[node.end_mark.index:]
    return out.replace(f"# {old}\n", f"# {instruction}\n", 1)


def publish_reworded(source: TaskVersion, instruction: str, record: dict) -> TaskVersion:
    """Publish ``v<N+1>`` of ``source``'s task: ``source`` with the spec's instruction replaced and ``record``
    (plus the source and both wordings) saved as its ``reword`` record. ``source`` is left untouched."""

    def reword(out: TaskLayout) -> dict:
        out.spec.write_text(replace_instruction(out.spec.read_text(), instruction))
        written = yaml.safe_load(out.spec.read_text())["instruction"]
        if written != instruction:
            raise RewordError(f"{source.env_id}: the rewritten spec reads {written!r}")
        return dict(record, old=source.spec.instruction, new=instruction)

    return publish_derived(source, "reword", reword)


__all__ = ["PROPOSAL_WORDINGS", "LibraryWording", "ProposalWording", "RewordError", "Rewording", "candidates_for",
           "plan_commands", "plan_rewording", "proposal_frames", "publish_reworded", "replace_instruction",
           "spec_frames"]
