"""Last step before commit, the solvability gate: does the solver actually solve the drafted task?

:func:`run_gate` runs the stage executor (the solver ``gendex collect`` uses) on :data:`GATE_ATTEMPTS` seeds of the
draft, seeds of their own (:func:`gate_seeds`: a range no dataset, benchmark or evaluation uses, drawn from the
task's name), in a **fresh child process**: the outcome does not depend on what ran before in the generator's
process, and the model-written task is exercised away from it. The task is committed only when at least
:data:`GATE_MIN_RATE` of the attempts succeed. It stops early once that can no longer happen.

A task that solves itself is no task: after the solver, the gate also runs the do-nothing policy (every joint
target held, :class:`gendex.solve.baselines.HoldSolver`) for the whole episode on :data:`NULL_ATTEMPTS` of the seeds,
and a draft it solves even once fails the gate (a laptop lid started at 1.2 rad falls shut by itself: 5 of 5
evaluation episodes of CloseLaptop13in-v0 were won by holding still).

The measurement is stored with the task (its ``solvability`` record): attempts, successes, env steps per success,
the failures by cause, the seeds and the solver's version. ``gendex list`` shows it. A task that fails the gate is
not committed; the pipeline records why and proposes again, telling the backend what failed (see
:func:`generator.pipeline.generate_task`).

Run alone: ``python -m generator.steps.gate FOLDER [--attempts K] [--min-rate R]`` on a task-version folder prints the
record as JSON.
"""

from __future__ import annotations

import argparse
import functools
import json
import logging
import shutil
import subprocess
import sys
import tempfile
import time
import zlib
from dataclasses import asdict, dataclass, field
from pathlib import Path

from generator.errors import GeneratorError

log = logging.getLogger(__name__)

GATE_ATTEMPTS = 10
"""Attempts per drafted task (the issue's K)."""
GATE_MIN_RATE = 0.8
"""Success rate a task needs to be committed."""
GATE_SEED_BASE = 50_000_000
"""Gate seeds start here: far above the seeds datasets (0..), benchmarks (1000-90000) and suites use."""
GATE_TIMEOUT_S = 900
"""The child process is killed after this long (the task counts as failed)."""
NULL_ATTEMPTS = 3
"""Gate seeds on which the do-nothing policy must fail."""


class GateError(GeneratorError):
    """The gate itself could not run (the child process crashed or timed out)."""


@dataclass(frozen=True)
class GateResult:
    """One gate run of a task draft."""

    attempts: int
    successes: int
    env_steps: int
    seeds: list[int]
    failures: dict[str, int] = field(default_factory=dict)
    """``stage/skill/cause`` -> attempts that failed so (:class:`gendex.solve.failure.Failure` keys)."""
    solver: str = "stages"
    solver_version: str = ""
    min_rate: float = GATE_MIN_RATE
    planned_attempts: int = GATE_ATTEMPTS
    """Attempts the gate would have run; fewer ran when the rate could no longer reach ``min_rate``."""
    null_attempts: int = 0
    """Seeds the do-nothing policy was run on (0: not run: records from before this check, or a draft the solver
    had already failed)."""
    null_successes: int = 0
    """Of those, how many it solved (any makes the task fail the gate)."""

    @property
    def rate(self) -> float:
        return self.successes / self.planned_attempts if self.planned_attempts else 0.0

    @property
    def passed(self) -> bool:
        return self.successes >= self.min_rate * self.planned_attempts - 1e-9 and self.null_successes == 0

    @property
    def env_steps_per_success(self) -> float | None:
        return self.env_steps / self.successes if self.successes else None

    def to_dict(self) -> dict:
        return asdict(self) | {"rate": self.rate, "passed": self.passed,
                               "env_steps_per_success": self.env_steps_per_success}

    def summary(self) -> str:
        """One line: the rate, and the commonest failures."""
        fails = ", ".join(f"{k} x{v}" for k, v in sorted(self.failures.items(), key=lambda kv: -kv[1])[:3])
        null = (f"; solved by doing nothing on {self.null_successes} of {self.null_attempts} seeds"
                if self.null_successes else "")
        return (f"{self.successes}/{self.attempts} solved (needs {self.min_rate:.0%} of {self.planned_attempts})"
                + (f"; failures: {fails}" if fails else "") + null)


def gate_seeds(name: str, k: int = GATE_ATTEMPTS) -> list[int]:
    """``k`` seeds of the gate for task ``name`` (stable, disjoint across names up to 100 000 of them)."""
    base = GATE_SEED_BASE + (zlib.crc32(name.encode()) % 100_000) * 100
    return list(range(base, base + k))


def solver_version() -> str:
    from generator.pipeline import generator_version

    return f"gendex {generator_version()} stage executor"


class _GateAttempter:
    """One worker's env and solver for gate attempts (``seed -> (succeeded, steps, failure key)``)."""

    def __init__(self, folder: str):
        from gendex.solve import SOLVER_ENV_KWARGS, SOLVERS
        from gendex_envs.registry import HISTORY_FREE, make_env
        from gendex_envs.task_version import TaskVersion

        self.env = make_env(TaskVersion.at(folder), obs_mode="state", **SOLVER_ENV_KWARGS["stages"], **HISTORY_FREE)
        self.solver = SOLVERS["stages"]()

    def __call__(self, seed: int) -> tuple[bool, int, str | None]:
        from gendex.solve.attempt import run_attempt

        r = run_attempt(self.env, self.solver, seed)
        return r.succeeded, r.steps, None if r.succeeded else r.failure.key


def measure(folder: Path, attempts: int = GATE_ATTEMPTS, min_rate: float = GATE_MIN_RATE,
            seeds: list[int] | None = None, workers: int = 1) -> GateResult:
    """Run the gate on task-version ``folder`` in this process (what the child process does). With ``seeds``, run
    the solver on exactly those (every one: no early stop) instead of the task's gate seeds: a re-measurement.
    ``workers`` > 1 runs the attempts in that many processes (:mod:`gendex.fanout`); they are judged in seed order
    with the same early stop, so the result is the one a single process gives."""
    import torch

    from gendex.fanout import Backend, ordered_map
    from gendex_envs.task_version import TaskVersion

    torch.set_num_threads(1)
    version = TaskVersion.at(folder)
    stop_early = seeds is None
    seeds = gate_seeds(version.name, attempts) if seeds is None else list(seeds)
    attempts = len(seeds)
    done, ok, steps, failures = 0, 0, 0, {}
    results = ordered_map(functools.partial(_GateAttempter, str(folder)), seeds, Backend.from_options(workers))
    try:
        for succeeded, n, failure in results:
            done += 1
            steps += n
            if succeeded:
                ok += 1
            else:
                failures[failure] = failures.get(failure, 0) + 1
            if stop_early and done - ok > (1 - min_rate) * attempts + 1e-9:
                break  # the rate can no longer reach min_rate
    finally:
        results.close()
    null_seeds = seeds[:NULL_ATTEMPTS] if ok >= min_rate * attempts - 1e-9 else []
    null_ok = 0
    if null_seeds:
        worker = _GateAttempter(str(folder))
        try:
            null_ok = sum(null_solves(worker.env, seed, version.spec.max_episode_steps) for seed in null_seeds)
        finally:
            worker.env.close()
    return GateResult(done, ok, steps, seeds[:done], failures, "stages", solver_version(), min_rate, attempts,
                      len(null_seeds), null_ok)


def null_solves(env, seed: int, steps: int) -> bool:
    """Whether holding every joint target for ``steps`` steps (the whole episode) solves ``env``'s task from
    ``seed``."""
    from gendex.solve.attempt import run_attempt
    from gendex.solve.baselines import HoldSolver

    return run_attempt(env, HoldSolver(steps=steps), seed).succeeded


def run_gate(draft: Path, name: str, attempts: int = GATE_ATTEMPTS, min_rate: float = GATE_MIN_RATE,
             timeout_s: float = GATE_TIMEOUT_S, workers: int = 1) -> GateResult:
    """The gate on a draft folder (task files, no version layout yet) of task ``name``, in a fresh child process
    (its attempts in ``workers`` processes)."""
    with tempfile.TemporaryDirectory(prefix="gendex-gate-") as tmp:
        folder = Path(tmp) / name / "v0"
        shutil.copytree(draft, folder)
        cmd = [sys.executable, "-m", "generator.steps.gate", str(folder), "--attempts", str(attempts),
               "--min-rate", str(min_rate), "--workers", str(workers)]
        t0 = time.perf_counter()
        try:
            out = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout_s, check=False)
        except subprocess.TimeoutExpired:
            raise GateError(f"the solvability gate of {name!r} ran past {timeout_s:.0f} s and was killed") from None
        if out.returncode != 0:
            tail = "\n".join(out.stderr.strip().splitlines()[-5:])
            raise GateError(f"the solvability gate of {name!r} crashed (exit {out.returncode}): {tail}")
        try:
            answer = json.loads(out.stdout.strip().splitlines()[-1])
        except (IndexError, ValueError):
            raise GateError(f"the solvability gate of {name!r} printed no result: {out.stdout[-300:]!r}") from None
        result = GateResult(**{k: v for k, v in answer.items() if k in GateResult.__dataclass_fields__})
        log.info("gate of %s: %s in %.0f s", name, result.summary(), time.perf_counter() - t0)
        return result


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", type=Path, help="a task-version folder (<Name>/v<N>)")
    ap.add_argument("--attempts", type=int, default=GATE_ATTEMPTS)
    ap.add_argument("--min-rate", type=float, default=GATE_MIN_RATE)
    ap.add_argument("--workers", type=int, default=1, help="processes running the attempts")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.WARNING, stream=sys.stderr)
    result = measure(args.folder, args.attempts, args.min_rate, workers=args.workers)
    sys.stdout.write(json.dumps(result.to_dict(), sort_keys=True) + "\n")


if __name__ == "__main__":
    main()
