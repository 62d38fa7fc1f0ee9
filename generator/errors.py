"""Typed errors of the task generator. Each names what was wrong and what is allowed, so it can be fed back."""

from __future__ import annotations

from gendex_envs import errors as runtime_errors
from gendex_envs.errors import GenDexError


class GeneratorError(GenDexError):
    """Base class of every error the generator raises on purpose."""


class InstructionError(GeneratorError, ValueError):
    """A request GenDex cannot turn into a task: a verb outside its skills, or an object that cannot play the part
    the verb needs. The message lists what is possible."""


class PromptError(GeneratorError, KeyError):
    """A prompt template is missing, or was rendered with a missing or unexpected variable."""

    def __str__(self) -> str:  # KeyError quotes its message; keep it readable
        return str(self.args[0]) if self.args else ""


class BackendError(GeneratorError, RuntimeError):
    """A model backend failed (no key, HTTP error after bounded retries, unknown model id, bad response)."""


class TranscriptMismatchError(BackendError):
    """A replayed run asked for a request the recorded transcript does not hold (or holds in another order)."""


class ModelOutputError(GeneratorError, ValueError):
    """A model answer could not be parsed into the record the step needs (malformed JSON / YAML / directives)."""


class ProposalError(ModelOutputError):
    """A proposal references objects that are not in the catalog, or misses required fields."""


class SceneError(ModelOutputError):
    """A scene YAML is malformed or violates the task schema."""


class DirectiveError(ModelOutputError):
    """A critic directive is malformed, names an unknown object or action, or leaves the allowed range."""


class RewardCodeError(ModelOutputError, runtime_errors.RewardCodeError):
    """Reward code was rejected: unsafe constructs, missing functions, or a failed simulator probe."""


class UnsafeCodeError(RewardCodeError, runtime_errors.UnsafeCodeError):
    """Reward code uses something it may not (imports, file/network/process access, dunder tricks, exec/eval)."""


class RewardProbeError(RewardCodeError):
    """Reward code failed when run in the simulator (exception, time limit, wrong shape/dtype/device, NaN)."""


class RetriesExhaustedError(GeneratorError):
    """A pipeline step kept failing after its bounded number of retries; the last reason is attached."""


class CommitError(GeneratorError, OSError):
    """A task folder could not be written atomically."""
