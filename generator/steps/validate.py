"""Step 5b, validate language-model reward code before it is committed: the static check, then the probe.

Reward modules (the task's and the stages', laid out as :class:`~gendex_envs.task_version.TaskLayout` says; interface
in :mod:`gendex_envs.reward_module`) are written by a language model, so they are untrusted. Two layers keep them in
check; every rejection raises a typed error whose message is fed back to the model verbatim, so it names the line
and the construct (static) or the function, step and observed vs expected value (probe):

1. :func:`check_reward_source` (:mod:`generator.steps.static_check`) rejects anything outside a small, pure-tensor
   subset of Python before the code runs.
2. :func:`probe_task` (:mod:`generator.steps.probe`) runs the modules in a child process against the real task env
   and checks every call.

:func:`validate_reward_module` is both layers for one module; :func:`validate_task` validates all modules of a task
and returns a JSON-able :class:`ValidationReport` instead of raising.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path

from generator.errors import RewardCodeError
from generator.steps.probe import (
    DEFAULT_MEMORY_LIMIT_MB,
    DEFAULT_STARTUP_TIMEOUT_S,
    DEFAULT_STEPS,
    DEFAULT_TIMEOUT_S,
    ModuleOutcome,
    ProbeReport,
    ValidationReport,
    module_display,
    probe_modules,
    probe_reward_module,
    probe_task,
    task_reward_modules,
)
from generator.steps.static_check import check_reward_file, check_reward_source

log = logging.getLogger(__name__)

__all__ = ["ModuleOutcome", "ProbeReport", "ValidationReport", "check_reward_file", "check_reward_source",
           "probe_reward_module", "probe_task", "task_reward_modules", "validate_reward_module", "validate_task"]


def validate_reward_module(task_dir: str | Path, module_path: str | Path, **probe_kwargs) -> ProbeReport:
    """Static check, then the simulator probe, of one module; returns the probe's report or raises."""
    task_dir = Path(task_dir)
    check_reward_file(module_path, module_display(task_dir, Path(module_path)))
    return probe_reward_module(task_dir, module_path, check_static=False, **probe_kwargs)


def validate_task(task_dir: str | Path, modules: list[str | Path] | None = None, *, steps: int = DEFAULT_STEPS,
                  timeout_s: float = DEFAULT_TIMEOUT_S, seed: int = 0, num_envs: int = 1,
                  sim_backend: str = "physx_cpu", memory_limit_mb: int | None = DEFAULT_MEMORY_LIMIT_MB,
                  startup_timeout_s: float = DEFAULT_STARTUP_TIMEOUT_S, check_static: bool = True) -> ValidationReport:
    """Validate every module (default: :func:`task_reward_modules`) and report each outcome; does not raise for
    rejected modules (see :meth:`ValidationReport.raise_first`), so the model can get every problem in one round.

    Modules that fail the static check are never run; the others are probed in one child process (a new one is
    started after a module had to be killed). ``check_static=False`` skips the static check (tests of the probe's
    own fences only: never for model output).
    """
    t0 = time.monotonic()
    task_dir = Path(task_dir)
    paths = [Path(m) for m in (task_reward_modules(task_dir) if modules is None else modules)]
    outcomes: dict[int, ModuleOutcome] = {}
    to_probe: list[int] = []
    for i, p in enumerate(paths):
        name = module_display(task_dir, p)
        try:
            if check_static:
                check_reward_file(p, name)
        except RewardCodeError as exc:
            outcomes[i] = ModuleOutcome(name, ok=False, failed_at="static", error_type=type(exc).__name__,
                                        error=str(exc))
            log.info("static check %s: rejected: %s", name, exc)
        else:
            to_probe.append(i)
    if to_probe:
        results = probe_modules(task_dir, [paths[i] for i in to_probe], steps=steps, timeout_s=timeout_s, seed=seed,
                         num_envs=num_envs, sim_backend=sim_backend, memory_limit_mb=memory_limit_mb,
                         startup_timeout_s=startup_timeout_s, stop_on_error=False, check_static=check_static)
        for i, r in zip(to_probe, results, strict=True):
            name = module_display(task_dir, paths[i])
            if isinstance(r, ProbeReport):
                outcomes[i] = ModuleOutcome(name, ok=True, probe=r)
            else:
                outcomes[i] = ModuleOutcome(name, ok=False, failed_at="probe", error_type=type(r).__name__,
                                            error=str(r))
    ordered = [outcomes[i] for i in range(len(paths))]
    return ValidationReport(task_dir=str(task_dir), ok=bool(ordered) and all(o.ok for o in ordered),
                            modules=ordered, steps=steps, seed=seed, wall_s=round(time.monotonic() - t0, 3))
