"""The second wall around untrusted reward code: a separate, OS-confined worker process.

The first wall (the static check, :mod:`gendex_envs.code_check`, and the runtime guard's restricted builtins,
:mod:`gendex_envs.guard`) keeps reward code to a pure-tensor subset of Python. Python has no in-process isolation,
so a hole in it would hand the code the whole process. Untrusted modules therefore run in a worker process
(:mod:`gendex_envs.sandbox.worker`) that, after importing torch and before it receives any source, confines itself
(:mod:`gendex_envs.sandbox.confine`): no new privileges and no capabilities; Landlock lets it read only the Python
installation and the system libraries, write nothing, bind or connect no TCP port and signal no other process;
a seccomp filter refuses exec, fork, sockets, ptrace, mounts, bpf, keys and raising its limits; rlimits cap its
address space, CPU time, open files and file size. The parent never unpickles what the worker sends: the wire
format is a bounded JSON header plus raw tensor bytes of allow-listed dtypes (:mod:`gendex_envs.sandbox.protocol`).

Reward functions get a view with the members of ``prompts/env_api.txt`` whose values come from a per-call snapshot
the parent takes from the real view (:func:`gendex_envs.reward_view.view_of`); a member missing from it is asked
of the parent within the call, and from then on sent with every call of that function (one round trip per call
after the first). Each call has a wall-clock limit (:data:`CALL_TIMEOUT_S`, ``GENDEX_SANDBOX_TIMEOUT_S``); a
worker that runs past it is killed and the call raises :class:`~gendex_envs.errors.RewardTimeoutError`.

The worker also records a function's call as a graph of torch operations (:mod:`gendex_envs.sandbox.trace`); the
parent checks it and replays later calls from it in its own process, through a table of allow-listed operations
only (:mod:`gendex_envs.sandbox.ops`, :mod:`gendex_envs.sandbox.replay`), so that a step needs no round trip; a
call a replay does not reproduce goes to the worker (``GENDEX_SANDBOX_REPLAY=0`` sends every call there). A system
that cannot confine the worker refuses untrusted modules (:class:`~gendex_envs.errors.RewardSandboxError`) unless
``GENDEX_IN_PROCESS_GUARD=1`` opts into the first wall alone. See ``docs/security.md``, "Isolation".
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from gendex_envs.errors import RewardModuleError
from gendex_envs.sandbox.host import (
    CALL_TIMEOUT_S,
    CPU_ENV,
    IN_PROCESS_ENV,
    MEMORY_ENV,
    TIMEOUT_ENV,
    RemoteModule,
    enabled,
    shared_worker,
)

__all__ = ["CALL_TIMEOUT_S", "CPU_ENV", "IN_PROCESS_ENV", "MEMORY_ENV", "TIMEOUT_ENV", "enabled", "load",
           "shared_worker"]


def _function(remote: RemoteModule, name: str, copied: int) -> Callable:
    from gendex_envs import reward_view

    info_of = getattr(reward_view, "reward_info", None)  # what the in-process wrapper passes as info

    def call(env, *args):
        if len(args) != copied:
            raise TypeError(f"{name} takes env and {copied} more arguments, got {len(args)}")
        info = args[-1] if copied else None
        if copied and info_of is not None:
            args = (*args[:-1], info_of(info))
        return remote.call(name, env, args, info)

    call.__name__ = call.__qualname__ = name
    return call


def load(path: Path, source: str, full_builtins: bool = False):
    """``path``'s module, from its already checked ``source`` text, loaded in this process's confined worker: a
    :class:`~gendex_envs.reward_module.RewardModule` whose functions run there. ``full_builtins`` (tests only)
    runs it with Python's ordinary builtins, as if the first wall had a hole."""
    from gendex_envs.reward_module import OPTIONAL_FUNCTIONS, REQUIRED_FUNCTIONS, RewardModule, checked_reward_max
    from gendex_envs.sandbox import host

    remote = RemoteModule(Path(path), source, full_builtins or host.FULL_BUILTINS_FOR_TESTS)
    missing = [f for f in REQUIRED_FUNCTIONS if f not in remote.functions]
    if missing:
        raise RewardModuleError(f"reward module {path} lacks {missing}; required: {list(REQUIRED_FUNCTIONS)}, "
                                f"optional: {list(OPTIONAL_FUNCTIONS)}")
    checked_reward_max(path, remote.reward_max)
    return RewardModule(path=Path(path), evaluate=_function(remote, "evaluate", 0),
                        compute_dense_reward=_function(remote, "compute_dense_reward", 3),
                        get_obs_extra=_function(remote, "_get_obs_extra", 1)
                        if "_get_obs_extra" in remote.functions else None,
                        reward_max=remote.reward_max)
