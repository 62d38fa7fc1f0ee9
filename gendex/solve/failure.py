"""Why an attempt failed: a typed reason for every attempt that did not succeed.

A :class:`Failure` names the cause (:data:`~gendex_envs.errors.FAILURE_CAUSES`), the stage and skill it happened
in, and a one-line detail. It comes from the :class:`~gendex_envs.errors.ExecutionError` a solver raised (the
executor's primitives say which cause), or, when the episode ended some other way, from how it ended:

* the env's time limit ran out -> ``timeout`` (in the stage the solver was running);
* the env terminated without success -> ``unstable_physics`` when the state went non-finite or a body flew off
  faster than :data:`UNSTABLE_SPEED_M_S`, else ``task_fail`` (the task's own failure condition, e.g. the object fell
  off the table);
* the solver finished without success -> ``target_not_reached`` (in its last stage).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import asdict, dataclass

import torch

from gendex_envs.errors import FAILURE_CAUSES, ExecutionError

UNSTABLE_SPEED_M_S = 20.0
"""A body moving faster than this has been launched by the solver, not moved by a robot."""


@dataclass(frozen=True)
class Failure:
    """Why one attempt failed."""

    cause: str
    """One of :data:`~gendex_envs.errors.FAILURE_CAUSES`."""
    stage: str | None = None
    skill: str | None = None
    detail: str = ""

    def __post_init__(self):
        if self.cause not in FAILURE_CAUSES:
            raise ValueError(f"unknown failure cause {self.cause!r}; causes: {sorted(FAILURE_CAUSES)}")

    @property
    def key(self) -> str:
        """``stage/skill/cause`` (``-`` where unknown): the finest grouping of a breakdown."""
        return f"{self.stage or '-'}/{self.skill or '-'}/{self.cause}"

    def __str__(self) -> str:
        where = f" in stage {self.stage!r} ({self.skill})" if self.stage else ""
        return f"{self.cause}{where}: {self.detail}" if self.detail else f"{self.cause}{where}"

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def of_error(cls, exc: ExecutionError) -> Failure:
        return cls(exc.cause, exc.stage, exc.skill, str(exc))

    @classmethod
    def of_ending(cls, solver, env, terminated: bool, truncated: bool) -> Failure:
        """The failure of an episode that ended without success and without an ExecutionError."""
        stage = getattr(solver, "current_stage", None)
        if stage is None and getattr(solver, "finished", False):
            stages = env.unwrapped.task_spec.stages
            stage = stages[-1] if stages else None
        name, skill = (stage.name, stage.skill) if stage is not None else (None, None)
        if terminated:
            if not physics_stable(env):
                return cls("unstable_physics", name, skill, "the simulation state went non-finite or exploded")
            return cls("task_fail", name, skill, "the task's failure condition ended the episode")
        if truncated:
            return cls("timeout", name, skill, "the episode's step limit was reached")
        return cls("target_not_reached", name, skill, "the solver finished without the task's success")


def physics_stable(env) -> bool:
    """True while every body's state is finite and nothing moves faster than :data:`UNSTABLE_SPEED_M_S`."""
    u = env.unwrapped
    state = u.get_state()
    if not bool(torch.isfinite(state).all()):
        return False
    for entity in u.objects.values():
        v = entity.linear_velocity if hasattr(entity, "linear_velocity") else entity.root_linear_velocity
        if float(torch.linalg.norm(v, dim=-1).max()) > UNSTABLE_SPEED_M_S:
            return False
    return True


def breakdown(failures: dict[str, int]) -> list[tuple[str, int]]:
    """``stage/skill/cause`` counts, most frequent first (ties by key)."""
    return sorted(failures.items(), key=lambda kv: (-kv[1], kv[0]))


def by_cause(failures: dict[str, int]) -> dict[str, int]:
    """Counts per cause of a ``stage/skill/cause`` breakdown."""
    out: Counter[str] = Counter()
    for key, n in failures.items():
        out[key.rsplit("/", 1)[-1]] += n
    return dict(out)


__all__ = ["UNSTABLE_SPEED_M_S", "Failure", "breakdown", "by_cause", "physics_stable"]
