"""Which code built a published dataset, and whether the code at hand would build the same one.

A dataset manifest (:mod:`gendex.data.datasets`) records, next to its checksums, what it was built with
(:class:`BuiltWith`): a *canary* (a digest of the first attempt of its first task: seed, steps, outcome, and the
recorded actions, states, rewards and success flags) and the commit. A few seconds of collecting tell whether the code
at hand behaves as the code that built the manifest did, so ``gendex dataset build`` says so *before* it collects for
minutes or hours, and CI can check every committed manifest without building it: one whose canary differs must
either be rebuilt (``gendex dataset build NAME --record``) or be marked as built by older code
(``gendex dataset stale NAME``). Checksums stay the proof of a byte-identical rebuild; the canary is the cheap
early sign.
"""

from __future__ import annotations

import functools
import hashlib
import logging
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gendex.data.numerics import NUMERICS

log = logging.getLogger(__name__)

CANARY_FORMAT = 1
"""Bumped when what the canary digests changes (old canaries then differ on purpose)."""


@dataclass(frozen=True)
class BuiltWith:
    """What built a manifest's recorded checksums."""

    canary: str = ""
    """SHA-256 (hex) of the first attempt of the manifest's first task under that code (:func:`canary`); empty when
    unknown (checksums recorded before canaries existed)."""
    commit: str = ""
    """The git commit of the checkout that built it, when known (informational)."""
    stale: bool = False
    """Marked by ``gendex dataset stale``: the checksums come from older code; a build now gives other files."""
    numerics: str = ""
    """The pinned numerics the build ran with (:data:`gendex.data.numerics.NUMERICS`); empty: the CPU's own kernels
    (builds before pinning, which only a CPU of the same kind reproduces)."""


def _digest_arrays(h, name: str, value) -> None:
    if value is None:
        h.update(f"{name}:none;".encode())
        return
    arr = np.ascontiguousarray(value)
    h.update(f"{name}:{arr.dtype.str}:{arr.shape};".encode())
    h.update(arr.tobytes())


def canary(manifest) -> str:
    """The canary of ``manifest`` under the code at hand: its first task's first attempt (seed ``task.seed``),
    collected exactly as a build collects it: in a worker process with pinned numerics."""
    from gendex.data.numerics import pinned_backend
    from gendex.fanout import ordered_map
    from gendex_envs.registry import resolve_task

    root = str(resolve_task(manifest.tasks[0].task).tasks_root)
    results = ordered_map(functools.partial(_canary_worker, manifest, root), [0], pinned_backend(None))
    try:
        return next(results)
    finally:
        results.close()


def _canary_worker(manifest, task_root: str):
    """A worker (:func:`gendex.fanout.ordered_map`) computing ``manifest``'s canary in its own process (its first
    task registered from ``task_root`` when the parent registered it at run time)."""
    import gymnasium as gym

    import gendex_envs  # noqa: F401
    from gendex.data import numerics
    from gendex_envs.registry import register_tasks, resolve_task

    numerics.check()
    if resolve_task(manifest.tasks[0].task).env_id not in gym.registry:
        register_tasks([Path(task_root)])
    return lambda _job: _canary_here(manifest)


def _canary_here(manifest) -> str:
    from gendex.data.collector import CollectConfig, attempt_once
    from gendex.solve import SOLVER_ENV_KWARGS, SOLVERS
    from gendex_envs.registry import resolve_task

    task = manifest.tasks[0]
    version = resolve_task(task.task)
    cfg = CollectConfig(task_id=version.env_id, num_success=1, out=Path("."), formats=(), cameras=manifest.cameras,
                        seed=task.seed, resolution=manifest.resolution, video_codec=manifest.video_codec,
                        **SOLVER_ENV_KWARGS[manifest.solver])
    episode, steps, failure = attempt_once(cfg, SOLVERS[manifest.solver], task.seed)
    h = hashlib.sha256(f"gendex-canary-{CANARY_FORMAT};{task.task};{task.seed};{steps};"
                       f"{failure.key if failure is not None else 'ok'};".encode())
    if episode is not None:
        for name in ("action", "state", "reward", "success", "fail", "environment_state"):
            _digest_arrays(h, name, getattr(episode, name))
    return h.hexdigest()


def current_commit() -> str:
    """The checkout's commit (``git rev-parse HEAD``), or "" outside a git checkout."""
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True, timeout=10,
                             cwd=Path(__file__).resolve().parent, check=False)
    except (OSError, subprocess.SubprocessError):
        return ""
    return out.stdout.strip() if out.returncode == 0 else ""


@dataclass(frozen=True)
class CodeCheck:
    """How the code at hand relates to the code that built a manifest."""

    name: str
    status: str
    """``same`` (canaries equal), ``stale`` (marked as built by older code), ``differs`` (canaries differ, not
    marked), ``unknown`` (no canary recorded and not marked) or ``unbuilt`` (no checksums recorded)."""
    canary: str
    message: str

    @property
    def ok(self) -> bool:
        """What CI accepts: the code builds what is recorded, or the manifest says it does not."""
        return self.status in ("same", "stale", "unbuilt")


def check_code(manifest, current: str | None = None) -> CodeCheck:
    """Compare ``manifest``'s recorded canary with the code at hand (``current``: an already computed canary)."""
    name, built = manifest.name, manifest.built_with
    refresh = f"`gendex dataset build {name} --record` rebuilds it and records the new checksums"
    if not manifest.checksums:
        return CodeCheck(name, "unbuilt", "", f"{name} records no checksums yet; {refresh}")
    if built is not None and built.stale:
        return CodeCheck(name, "stale", "", f"{name} was built by older code (commit {built.commit or 'unknown'}): "
                                            f"a build now gives other files than its checksums; {refresh}")
    current = canary(manifest) if current is None else current
    if built is None or not built.canary:
        return CodeCheck(name, "unknown", current,
                         f"{name} does not record which code built it; {refresh}, or `gendex dataset stale {name}` "
                         f"marks it as built by older code")
    if built.canary == current:
        return CodeCheck(name, "same", current, f"{name}: this code collects as the code that built it "
                                                f"(commit {built.commit or 'unknown'})")
    why = "" if built.numerics == NUMERICS else (
        f" (it was built with {built.numerics or 'its CPU' + chr(39) + 's own'} numerics, this code pins {NUMERICS})")
    return CodeCheck(name, "differs", current,
                     f"{name} was built by other code (commit {built.commit or 'unknown'}){why}: this code collects "
                     f"its first attempt differently, so a build will not match its checksums; {refresh}, or "
                     f"`gendex dataset stale {name}` marks it as built by older code")
