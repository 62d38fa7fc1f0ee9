"""The generator's side of the static check of reward code: :mod:`gendex_envs.code_check` with the generator's
error types (:class:`~generator.errors.UnsafeCodeError`, :class:`~generator.errors.RewardCodeError`), whose
messages are fed back to the model. The rules and the checker live in the runtime, which also checks untrusted
task folders when it loads them."""

from __future__ import annotations

from pathlib import Path

from gendex_envs import code_check
from gendex_envs import errors as runtime_errors
from generator.errors import RewardCodeError, UnsafeCodeError


def _translated(check, *args):
    try:
        return check(*args)
    except runtime_errors.UnsafeCodeError as exc:
        if isinstance(exc, UnsafeCodeError):
            raise
        raise UnsafeCodeError(str(exc)) from None
    except runtime_errors.RewardCodeError as exc:
        if isinstance(exc, RewardCodeError):
            raise
        raise RewardCodeError(str(exc)) from None


def check_reward_source(source: str, filename: str = "<reward module>") -> None:
    """:func:`gendex_envs.code_check.check_reward_source`, raising the generator's error types."""
    _translated(code_check.check_reward_source, source, filename)


def check_reward_file(path: str | Path, filename: str | None = None) -> str:
    """:func:`gendex_envs.code_check.check_reward_file` (the file read once, strictly as UTF-8; returns the checked
    text), raising the generator's error types."""
    return _translated(code_check.check_reward_file, path, filename)
