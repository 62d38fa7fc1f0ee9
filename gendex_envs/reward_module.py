"""Load a reward module of a task version (the task's, or one stage's; :class:`~gendex_envs.task_version.TaskLayout`).

A reward module is a small file of pure functions of the env state, all batched over ``[num_envs]``. It shapes
learning; it does not decide success, which the spec declares (:mod:`gendex_envs.success`):

``evaluate(env) -> dict[str, Tensor]``
    may contain ``fail`` ([N] bool: the episode failed, e.g. the object fell off the table; it vetoes success) and
    any [N] diagnostics the reward and observations use. It must not contain ``success``.
``compute_dense_reward(env, obs, action, info) -> Tensor``
    [N] float reward; ``info`` is what ``evaluate`` returned, with ``success`` and ``fail`` decided.
``_get_obs_extra(env, info) -> dict[str, Tensor]``  (optional)
    task observations, each [N, ...].
``REWARD_MAX: float``  (optional, default 1.0)
    upper bound of the dense reward, used by ``compute_normalized_dense_reward``.

The functions receive a :class:`~gendex_envs.reward_view.RewardView` as ``env``, never the env itself: the
documented members as fresh tensors, no handle to the scene, agent or controller. ``obs``, ``action`` and ``info``
are copies. The wrapping happens here, once, so every caller (the env, the judge, the probe, the solver) passes the
env and the module sees only the view.

Modules written by a language model are validated by the generator before they are committed. A module that is not
trusted (anything but a reviewed task the repository's trust record lists, unless the user trusts it) is checked
again here, statically, before it runs, and runs under the runtime guard (:mod:`gendex_envs.guard`). Every module,
trusted or not, is read once as UTF-8 and that exact text is checked and run: nothing is imported from the task
folder, so a ``coding:`` declaration, a byte-order mark or a ``__pycache__`` shipped with it cannot change what
runs, and files the task layout does not name are ignored.
"""

from __future__ import annotations

import hashlib
import logging
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

from gendex_envs import guard
from gendex_envs.code_check import check_reward_source
from gendex_envs.code_check.source import compile_reward_source, decode_reward_source, read_reward_bytes
from gendex_envs.errors import RewardCodeError, RewardModuleError
from gendex_envs.reward_view import view_args, view_of

log = logging.getLogger(__name__)

REQUIRED_FUNCTIONS = ("evaluate", "compute_dense_reward")
OPTIONAL_FUNCTIONS = ("_get_obs_extra",)


@dataclass(frozen=True)
class RewardModule:
    """The functions of one task's reward module."""

    path: Path
    evaluate: Callable
    compute_dense_reward: Callable
    get_obs_extra: Callable | None
    reward_max: float


def load_reward_module(path: str | Path, trusted: bool | None = None, static_check: bool = True) -> RewardModule:
    """Run ``path`` as a private module and check its interface; raises :class:`RewardModuleError`.

    The file is read once, strictly as UTF-8 (:func:`~gendex_envs.code_check.source.read_reward_source`: a
    ``coding:`` declaration or byte-order mark naming another encoding is refused), and that exact text is
    checked, compiled and executed in a fresh module namespace. Nothing is imported from the folder's path, so no
    ``__pycache__`` is read or written and no other file of the folder (extra ``.py``, ``.pyc``, ``.so``) is looked
    at. This is one code path for trusted and untrusted modules; the code objects name the real path, by which the
    runtime guard's audit hook recognises untrusted frames.

    ``trusted`` defaults to the file's trust (:func:`gendex_envs.guard.is_trusted`: a reward module of the
    repository's task folder whose bytes the trust record lists, or ``trust_remote_code``; the bytes read are the
    bytes judged). An untrusted module is first statically checked
    (:func:`gendex_envs.code_check.check_reward_source`; a rejection is a :class:`RewardModuleError` listing every
    problem, raised before any of its code runs), then its folder goes under the runtime guard's audit hook and it
    runs with restricted builtins and read-only copies of its modules (:mod:`gendex_envs.guard`), in the confined
    worker process (:mod:`gendex_envs.sandbox`; ``GENDEX_IN_PROCESS_GUARD=1`` runs it in this process instead). An
    untrusted module that is a link is refused: trust is judged where a file lies. ``static_check=False`` skips the
    static check of an untrusted module (the probe's tests of the runtime fences); the guard applies either way."""
    named = Path(path).absolute()
    path = named.parent.resolve() / named.name  # its folder resolved; a link is judged where it lies (guard.is_trusted)
    if not path.is_file():
        raise RewardModuleError(f"reward module {path} does not exist; every task version needs a task reward module")
    judged = trusted is None
    trusted = guard.is_trusted(path) if judged else trusted
    if not trusted and path.is_symlink():
        raise RewardModuleError(f"reward module {path} is a link (to {path.resolve()}); an untrusted folder's reward "
                                "modules must be regular files of that folder")
    try:
        data = read_reward_bytes(path)
        if judged and trusted and not guard.is_trusted(path, data):  # what runs is what the trust record lists
            raise RewardModuleError(f"reward module {path} changed while it was being loaded; load it again")
        source = decode_reward_source(data, str(path))
    except RewardCodeError as exc:
        raise RewardModuleError(f"reward module {path} was refused before any of it ran: {exc}") from exc
    if not trusted:
        if static_check:
            try:
                check_reward_source(source, str(path))
            except RewardCodeError as exc:
                raise RewardModuleError(
                    f"reward module {path} is not trusted (not a reviewed task recorded in the repository's "
                    f"generated_tasks/TRUSTED.sha256) and the static check rejected it before any of it ran; "
                    f"trust_remote_code=True runs a folder you wrote as it is.\n{exc}") from exc
        guard.untrust(path.parent)
        from gendex_envs import sandbox  # here: the sandbox builds RewardModules of this module

        if sandbox.enabled():  # the second wall: a confined worker process runs it (gendex_envs.sandbox)
            return sandbox.load(path, source)
    digest = hashlib.sha1(str(path).encode()).hexdigest()[:10]
    name = f"gendex_reward_{path.parent.parent.name}_{path.parent.name}_{digest}"
    module = ModuleType(name)
    module.__file__ = str(path)
    if not trusted:
        module.__dict__["__builtins__"] = guard.restricted_builtins()
    try:
        code = compile_reward_source(source, path)
        exec(code, module.__dict__)  # the checked text, compiled here: never the folder's own bytecode
    except Exception as exc:
        raise RewardModuleError(f"reward module {path} failed to import: {type(exc).__name__}: {exc}") from exc
    # registered like an imported module, so pickle, inspect and warnings can find its functions by __module__
    sys.modules.setdefault(name, module)
    missing = [f for f in REQUIRED_FUNCTIONS if not callable(getattr(module, f, None))]
    if missing:
        raise RewardModuleError(
            f"reward module {path} lacks {missing}; required: {list(REQUIRED_FUNCTIONS)}, optional: "
            f"{list(OPTIONAL_FUNCTIONS)}"
        )
    reward_max = checked_reward_max(path, getattr(module, "REWARD_MAX", 1.0))
    extra = getattr(module, "_get_obs_extra", None)
    return RewardModule(path=path, evaluate=_through_view(module.evaluate, 0),
                        compute_dense_reward=_through_view(module.compute_dense_reward, 3),
                        get_obs_extra=_through_view(extra, 1) if callable(extra) else None, reward_max=reward_max)


REWARD_MAX_RANGE = (1e-3, 1e6)
"""Bounds of a module's ``REWARD_MAX`` (committed modules use 3 to 7): the env's normalized reward divides by it, so
a tiny one turns every finite reward into inf."""


def checked_reward_max(path: Path, value) -> float:
    """``value`` as a module's ``REWARD_MAX``: a real number within :data:`REWARD_MAX_RANGE`, else
    :class:`RewardModuleError` naming the module, the value and the range."""
    low, high = REWARD_MAX_RANGE
    number = float(value) if isinstance(value, int | float) and not isinstance(value, bool) else None
    if number is None or not low <= number <= high:
        raise RewardModuleError(f"reward module {path}: REWARD_MAX={str(value)[:40]} must be a number from {low} to "
                                f"{high:g} (the normalized reward divides by it)")
    return number


def _through_view(fn: Callable, copied: int) -> Callable:
    """``fn`` called with the env's :class:`~gendex_envs.reward_view.RewardView` in place of the env and copies of
    its ``copied`` further arguments (obs, action, info). The last of them, ``info``, lacks the env's bookkeeping
    (:func:`~gendex_envs.reward_view.reward_info`: no ``elapsed_steps``). What ``fn`` returns is checked where
    the env and the judge take it (:mod:`gendex_envs.reward_checks`), so a module built otherwise is checked too."""
    from gendex_envs.reward_view import reward_info  # here, not at the top: this function's own dependency

    def call(env, *args):
        if len(args) != copied:
            raise TypeError(f"{fn.__name__} takes env and {copied} more arguments, got {len(args)}")
        if copied:
            args = (*args[:-1], reward_info(args[-1]))
        return fn(view_of(env), *(view_args(a) for a in args))
    call.__name__ = call.__qualname__ = fn.__name__
    call.__wrapped__ = fn
    return call
