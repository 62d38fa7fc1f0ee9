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


class ControlModeError(GenDexError, ValueError):
    """An unknown control_joint mode or controller name."""


class ExecutionError(GenDexError):
    """A scripted solver's primitive could not run (no reachable grasp, no plan, unsupported stage)."""


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
