"""Typed errors raised by GenDex for bad input. Every message names what was wrong and what is allowed."""

from __future__ import annotations

import difflib
from collections.abc import Iterable


class GenDexError(Exception):
    """Base class of every error GenDex raises on purpose."""


class TaskSpecError(GenDexError, ValueError):
    """A task YAML is malformed: unknown key, wrong type, or a value outside what is allowed."""


class AssetNotFoundError(GenDexError, KeyError):
    """An asset id is not in the catalog."""

    def __str__(self) -> str:  # KeyError quotes its message; keep it readable
        return str(self.args[0]) if self.args else ""


class TaskNotFoundError(GenDexError, LookupError):
    """A task id or task folder does not exist in the registry."""


class DuplicateTaskError(GenDexError, ValueError):
    """A task id is registered twice."""


class RewardModuleError(GenDexError, ImportError):
    """A task's reward module is missing, fails to import or lacks a required function."""


class RewardSandboxError(GenDexError, RuntimeError):
    """Untrusted reward code could not run in the sandbox's confined worker: the system cannot confine one, the
    worker died or hit a limit, or its reply broke the wire format (:mod:`gendex_envs.sandbox`)."""


class RewardTimeoutError(RewardSandboxError, TimeoutError):
    """A call of untrusted reward code ran past the sandbox's wall-clock limit (the worker was stopped)."""


class RewardCodeError(GenDexError, ValueError):
    """Reward code does not parse or lacks its interface (the static check, :mod:`gendex_envs.code_check`)."""


class UnsafeCodeError(RewardCodeError):
    """Reward code uses something outside the allowed subset (files, processes, dunders, writes into the env...)."""


class ControlModeError(GenDexError, ValueError):
    """An unknown control_joint mode or controller name."""


FAILURE_CAUSES: dict[str, str] = {
    "no_ik": "no IK solution reaches the pose a primitive needs",
    "no_plan": "no collision-free arm motion was found",
    "grasp_failed": "the grasp did not close on the object or did not hold it",
    "slipped": "the object slipped out of the hand while lifting or carrying",
    "target_not_reached": "the stage ended without reaching its goal",
    "timeout": "the episode's step limit ended the attempt",
    "unstable_physics": "the simulation went unstable (non-finite or exploding state)",
    "task_fail": "the task's own failure condition ended the episode",
    "unsupported": "the solver has no primitive for the stage's skill on its target",
}
"""Why a solver's attempt failed: cause -> meaning (the keys of ``gendex collect``'s failure breakdown)."""


class ExecutionError(GenDexError):
    """A solver's attempt could not go on: which ``cause`` (:data:`FAILURE_CAUSES`), in which stage and skill."""

    def __init__(self, message: str, cause: str = "target_not_reached", stage: str | None = None,
                 skill: str | None = None):
        if cause not in FAILURE_CAUSES:
            raise ValueError(f"unknown failure cause {cause!r}; causes: {sorted(FAILURE_CAUSES)}")
        super().__init__(message)
        self.cause = cause
        self.stage = stage
        self.skill = skill

    def __reduce__(self):  # keep the cause through pickling (worker processes)
        return (type(self), (str(self), self.cause, self.stage, self.skill))


class StageError(GenDexError, ValueError):
    """A task stage does not exist, or a stage env lacks what it needs (start states, a policy)."""


class RenderModeError(GenDexError, ValueError):
    """A render mode that does not exist, or that this machine cannot serve (a viewer without a display)."""


class PolicyError(GenDexError, ValueError):
    """A trained policy does not fit the stage it is used for (observation or action size, control mode)."""


def suggest(name: str, options: Iterable[str], n: int = 3) -> str:
    """Return ' Did you mean: a, b?' for close matches of ``name`` among ``options`` (or '')."""
    matches = difflib.get_close_matches(str(name), [str(o) for o in options], n=n, cutoff=0.5)
    return f" Did you mean: {', '.join(repr(m) for m in matches)}?" if matches else ""
