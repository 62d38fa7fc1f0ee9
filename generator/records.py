"""Typed records passed between the generator's pipeline steps. Each is JSON-able (``to_json``) and saved with the
task."""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from typing import Any

ROLES = ("graspable", "container", "articulated", "support")
PROPOSAL_CONDITION_TYPES = ("lifted", "inside", "joint_open", "joint_at", "near", "over", "placed", "wiped", "hung",
                            "poured", "flipped")
"""Success condition types a proposal may state (the task's success; stages get theirs in the plan step)."""


def to_json(record: Any) -> str:
    return json.dumps(asdict(record), indent=2, sort_keys=True) + "\n"


@dataclass(frozen=True)
class ProposedObject:
    name: str
    asset: str
    role: str
    color: str | None = None
    """The named colour the task paints it (``gendex_envs.attributes.COLORS``); None: the asset's own."""
    starts_in: str | None = None
    """The name of the proposal's container this object starts inside (*take the apple out of the bowl*)."""
    fill: dict[str, Any] | None = None
    """What a vessel to pour from holds: ``{"asset": <a catalog piece, tag pourable>, "count": <pieces>}``; GenDex
    lays the pieces in it (:func:`gendex_envs.pouring.lay_pieces`), each its own object of the task."""


@dataclass(frozen=True)
class ProposedStep:
    skill: str
    """One of :data:`gendex_envs.spec.SKILLS`."""
    target: str
    control_joint: str
    instruction: str


@dataclass(frozen=True)
class Proposal:
    """What the task is: objects from the catalog, atomic steps (a skill on a target each), and checkable success
    conditions (one, or one per part of a composed task)."""

    name: str
    description: str
    objects: tuple[ProposedObject, ...]
    steps: tuple[ProposedStep, ...]
    success: dict[str, Any]
    success_text: str
    instruction: str | None = None
    """The human instruction this proposal answers (human-guided mode), else None."""
    substitutions: dict[str, str] = field(default_factory=dict)
    """Requested object -> catalog asset used instead (human-guided mode): the catalog lacked it, or the request
    named only a kind of object ('a fruit'), or the backend chose another object than the one named."""
    reading: dict[str, Any] | None = None
    """How the instruction was read before any backend was asked (:class:`generator.instruction.Reading`)."""
    also: tuple[dict[str, Any], ...] = ()
    """Further success conditions that must hold as well: a composed task (*close the microwave, then put the apple
    into the bowl*) has one per part."""

    @property
    def conditions(self) -> tuple[dict[str, Any], ...]:
        """Every success condition of the task: :attr:`success`, then :attr:`also`."""
        return (self.success, *self.also)


@dataclass(frozen=True)
class SceneCandidate:
    index: int
    yaml_text: str
    score: float
    """Lower is better: number of static check violations (+100 when the YAML did not parse)."""
    problems: tuple[str, ...]


@dataclass(frozen=True)
class CritiqueRound:
    """One refinement round: what the critic found and the directives applied."""

    round: int
    violations: tuple[str, ...]
    analysis: str
    directives: tuple[str, ...]
    rejected: tuple[str, ...] = ()
    """Directives or answers that could not be applied, with the reason (fed back)."""


@dataclass(frozen=True)
class RefineLog:
    rounds: tuple[CritiqueRound, ...]
    violations_before: int
    violations_after: int
    remaining: tuple[str, ...] = ()
    """Error violations still measured after the last round."""


@dataclass(frozen=True)
class RewardAttempt:
    module: str
    """The module's path in the task folder."""
    attempt: int
    ok: bool
    feedback: str


@dataclass(frozen=True)
class GenerationInfo:
    """Provenance saved as the version's generation record: enough to rerun the exact generation."""

    generator_version: str
    backend: str
    model: str
    is_language_model: bool
    seed: int
    index: int
    instruction: str | None
    command: str
    dropped: tuple[str, ...] = ()
    """Proposals dropped before this one, each with its reason (unsound scene, failed solvability gate)."""
