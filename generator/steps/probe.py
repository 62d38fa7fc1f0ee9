"""The reward probe: candidate modules run in a child process against the real task env, every call checked.

:func:`probe_task` / :func:`probe_reward_module` run the modules in a child process (see
:mod:`generator.steps.probe_child`) so that an infinite loop, a segfault or a memory blow-up cannot take down
the generator: the child builds the task's env once, swaps each candidate module in, resets and steps seeded
random actions and checks every call (``evaluate`` returns a ``fail`` bool ``[N]`` on the env's device and no
``success``, which the spec declares; a finite float ``[N]`` reward; finite ``[N, ...]`` observations). The
parent enforces the time and memory limits and turns every failure into
:class:`~generator.errors.RewardProbeError`.

Process hygiene: nothing the probe starts or writes may outlive the parent, even a parent killed with ``SIGKILL``
(whose ``finally`` blocks and :class:`tempfile.TemporaryDirectory` cleanup never run) or a parent that hangs.

* The child dies with its parent: it asks the kernel for ``SIGKILL`` at the parent's death (``PR_SET_PDEATHSIG``)
  before it imports anything untrusted, and checks right after that its parent is still the one named in the job
  (the parent may have died before the ``prctl``). Without ``prctl`` (not Linux) a thread polls ``os.getppid``.
* The child raises the sandbox worker's kernel walls around itself before the first candidate (Landlock, seccomp,
  no privileges; :func:`generator.steps.probe_child._confine`): a candidate past the static check and the runtime
  guard still writes, connects and spawns nothing. Where the system cannot raise them, the probe raises
  :class:`~gendex_envs.errors.RewardSandboxError` unless ``GENDEX_IN_PROCESS_GUARD=1``.
* The child limits its own CPU time (``RLIMIT_CPU``, budgets computed here from the job: ``startup_timeout_s`` and
  ``timeout_s`` per module, times :data:`CPU_MARGIN`), so a hung module is ended by the kernel even when no parent
  watches it; the parent reports such a death as "exceeded its CPU budget of N s".
* The temporary folder (job, progress, log) is removed by a *reaper*: a tiny process (stdlib only) started next to
  each child, in its own session, whose stdin is a pipe whose write end only the parent holds. The parent writes
  the child's process-group id into it, and ``done`` once it has cleaned up itself. When the parent dies, however it
  dies, the kernel closes the pipe; the reaper reads end-of-file without ``done``, kills the child's process group
  (a second path besides ``PDEATHSIG``, portable to any POSIX system) and removes the folder, then exits. A
  watchdog inside the child could not do this: the child may be the process that is stuck, and ``PDEATHSIG``
  kills it with no chance to run code.
* In the parent, ``finally`` blocks kill the child and remove the folder on any exception, ``KeyboardInterrupt``
  included; while a probe runs in the main thread, ``SIGTERM`` (when nothing else handles it) raises
  :class:`SystemExit` so that those blocks run too.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
import os
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

from gendex_envs.errors import GenDexError, TaskNotFoundError
from gendex_envs.task_version import TaskLayout
from generator.errors import GeneratorError, RewardCodeError, RewardProbeError, UnsafeCodeError
from generator.steps.static_check import check_reward_file

log = logging.getLogger(__name__)

DEFAULT_STEPS = 20
DEFAULT_TIMEOUT_S = 60.0
DEFAULT_MEMORY_LIMIT_MB = 4096
DEFAULT_STARTUP_TIMEOUT_S = 300.0
"""Time allowed to import the simulator and build the env (not charged to any module)."""
CPU_MARGIN = 2.0
"""CPU budgets are this multiple of the wall-clock limits (CPU time counts every thread), plus :data:`CPU_SLACK_S`."""
CPU_SLACK_S = 5.0
MAX_FILE_MB = 256
"""Largest file the child may write (``RLIMIT_FSIZE``; its log and progress files)."""
_POLL_S = 0.05
_REAPER_WAIT_S = 5.0
_STACK_WAIT_S = 2.0
FIRST_WALL_DOWN_FOR_TESTS = False
"""Tests only (``tests/security/test_probe_confinement.py``): the child loads every candidate as if the first wall
had a hole (no static check, Python's ordinary builtins, neither the runtime guard's audit hook nor the probe's
own), so that a test reaches the kernel's walls behind it. No parameter, job option of a caller or file of a task
folder sets it; only code running in this process can."""
_FRAME_RE = re.compile(r'File "(?P<file>[^"]+)", line (?P<line>\d+) in (?P<fn>\S+)')

CHILD_ENV_NAMES = frozenset({"PATH", "HOME", "LANG", "LANGUAGE", "TMPDIR", "TZ", "LD_LIBRARY_PATH", "DISPLAY",
                             "PYTHONPATH", "PYTHONHASHSEED", "PYTHONDONTWRITEBYTECODE", "PYTHONUNBUFFERED",
                             "PYTHONFAULTHANDLER", "PYTHONWARNINGS"})
CHILD_ENV_PREFIXES = ("LC_", "GENDEX_", "OMP_", "MKL_", "OPENBLAS_", "TORCH_", "CUDA_", "NVIDIA_", "VK_", "MESA_",
                      "SAPIEN_", "MS_", "XDG_")
"""The parent's environment variables the probe's child gets: the locale, paths, thread counts and the simulator's
and GenDex's own settings. Everything else (API keys, tokens, cloud credentials) stays in the parent: a candidate
past the first wall could put what it reads into an error message, which goes back to the model."""


def child_environment() -> dict[str, str]:
    """The environment the probe's child (and its reaper) start with: :data:`CHILD_ENV_NAMES` and names with one of
    :data:`CHILD_ENV_PREFIXES`."""
    return {k: v for k, v in os.environ.items() if k in CHILD_ENV_NAMES or k.startswith(CHILD_ENV_PREFIXES)}


@dataclass
class ProbeReport:
    """What probing one reward module observed (JSON-able with :func:`dataclasses.asdict`)."""

    module: str
    """The module's path relative to the task folder (as :meth:`TaskLayout.relative` shows it)."""
    path: str
    steps: int
    """Random-action steps run after the reset."""
    num_envs: int
    reward_min: float
    reward_max: float
    reward_mean: float
    success_rate: float
    """Fraction of (step, env) samples, the reset included, where ``success`` was True."""
    fail_rate: float
    obs_extra: dict[str, list[int]]
    """Shape per env of each ``_get_obs_extra`` entry."""
    wall_s: float
    """Seconds to import, reset and step the module in the probe process."""
    warnings: list[str] = field(default_factory=list)
    """Suspicious but allowed observations (reward above REWARD_MAX, constant reward, warnings raised, ...)."""


@dataclass
class ModuleOutcome:
    """Validation outcome of one module."""

    module: str
    ok: bool
    failed_at: str | None = None
    """``static`` or ``probe`` when rejected."""
    error_type: str | None = None
    """Class name of the error: ``UnsafeCodeError``, ``RewardCodeError`` or ``RewardProbeError``."""
    error: str | None = None
    """The error message, ready to be fed back to the model."""
    probe: ProbeReport | None = None


@dataclass
class ValidationReport:
    """Outcome of validating every reward module of a task (JSON-able with :func:`dataclasses.asdict`)."""

    task_dir: str
    ok: bool
    modules: list[ModuleOutcome]
    steps: int
    seed: int
    wall_s: float

    def failures(self) -> list[ModuleOutcome]:
        return [m for m in self.modules if not m.ok]

    def raise_first(self) -> None:
        """Raise the first module's error again, with its type (no-op when every module passed)."""
        for m in self.failures():
            cls = {"UnsafeCodeError": UnsafeCodeError, "RewardProbeError": RewardProbeError}.get(
                m.error_type or "", RewardCodeError)
            raise cls(m.error)

    def to_json(self) -> str:
        return json.dumps(dataclasses.asdict(self), indent=2, allow_nan=True)


def task_reward_modules(task_dir: str | Path) -> list[Path]:
    """The reward modules of a task folder: the task's, then the stages' (sorted)."""
    return TaskLayout(task_dir).reward_modules()


def module_display(task_dir: Path, module: Path) -> str:
    shown = TaskLayout(task_dir).relative(module)
    return shown if not Path(shown).is_absolute() else module.name


def _when(step: int | None) -> str:
    if step is None:
        return "while importing it"
    return "right after reset (step 0)" if step == 0 else f"at step {step}"


def _source_line(path: Path, line: int) -> str:
    try:
        return path.read_text(encoding="utf-8").splitlines()[line - 1].strip()
    except (OSError, IndexError, UnicodeDecodeError):
        return ""


def _stack_location(log_text: str, module: Path) -> str:
    """`` at line N (`code`)`` from the newest faulthandler dump's innermost frame in ``module`` ('' if none)."""
    target = module.resolve()
    for m in _FRAME_RE.finditer(log_text):  # frames come most recent first
        try:
            if Path(m["file"]).resolve() == target:
                code = _source_line(target, int(m["line"]))
                return f" at line {m['line']}" + (f" (`{code}`)" if code else "") + f" in {m['fn']}"
        except OSError:
            continue
    return ""


def _rss_kb(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return 0


def _cpu_s(pid: int) -> float:
    """CPU seconds (user + system) that process ``pid`` has used so far, from ``/proc`` (0 where unavailable)."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return 0.0


def cpu_budgets(timeout_s: float, startup_timeout_s: float, module_cpu_s: float | None = None) -> tuple[int, int]:
    """(CPU seconds to build the env, CPU seconds per module) that a probe child allows itself."""
    startup = math.ceil(CPU_MARGIN * startup_timeout_s + CPU_SLACK_S)
    module = math.ceil(module_cpu_s if module_cpu_s is not None else CPU_MARGIN * timeout_s + CPU_SLACK_S)
    return startup, max(module, 1)


def _setup_error(task_dir: Path, record: dict) -> GenDexError:
    """The env could not be built: not the reward's fault; keep GenDex's own error type where there is one."""
    import gendex_envs.errors as gerr

    cls = getattr(gerr, record.get("type", ""), None)
    if cls is gerr.RewardSandboxError:  # the child cannot be confined: it refused to run any candidate
        return cls(f"the reward probe did not probe the candidates of {task_dir}: {record.get('message')}")
    text = f"the reward probe could not build the env of {task_dir}: {record.get('type')}: {record.get('message')}"
    if isinstance(cls, type) and issubclass(cls, GenDexError):
        return cls(text)
    return GeneratorError(text + "\n" + record.get("traceback", ""))


class _Child:
    """One probe process over ``modules``; :meth:`run` returns ``{index: ProbeReport | RewardCodeError}``."""

    def __init__(self, task_dir: Path, modules: list[Path], displays: list[str], *, steps: int, timeout_s: float,
                 seed: int, num_envs: int, sim_backend: str, memory_limit_mb: int | None, startup_timeout_s: float,
                 stop_on_error: bool, workdir: Path, module_cpu_s: float | None = None, check_static: bool = True):
        self.task_dir, self.modules, self.displays = task_dir, modules, displays
        self.timeout_s, self.memory_limit_mb, self.startup_timeout_s = timeout_s, memory_limit_mb, startup_timeout_s
        self.workdir = workdir
        self.progress_path = workdir / "progress.jsonl"
        self.log_path = workdir / "child.log"
        layout = TaskLayout(task_dir)
        self.cpu_startup_s, self.cpu_module_s = cpu_budgets(timeout_s, startup_timeout_s, module_cpu_s)
        self.job = {"spec": str(layout.spec), "modules": [str(m) for m in modules], "displays": displays,
                    "stages": [layout.module_stage(m) for m in modules],
                    "steps": steps, "seed": seed, "num_envs": num_envs, "sim_backend": sim_backend,
                    "memory_limit_mb": memory_limit_mb, "stop_on_error": stop_on_error, "check_static": check_static,
                    "progress": str(self.progress_path), "parent_pid": os.getpid(),
                    "cpu_startup_s": self.cpu_startup_s, "cpu_module_s": self.cpu_module_s,
                    "max_file_mb": MAX_FILE_MB, "first_wall_down_for_tests": bool(FIRST_WALL_DOWN_FOR_TESTS)}
        self.results: dict[int, ProbeReport | RewardCodeError] = {}
        self.current: int | None = None
        self.started_at = 0.0
        self.last_call: tuple[str | None, int | None] = (None, None)
        self.ready = False
        self.walls: list[str] = []
        """The kernel walls the child raised before the first candidate (its ``ready`` event)."""
        self.baseline_rss_kb = 0
        self.cpu_seen_s = 0.0
        self.cpu_at_module_s = 0.0

    def run(self) -> dict[int, ProbeReport | RewardCodeError]:
        job_path = self.workdir / "job.json"
        job_path.write_text(json.dumps(self.job), encoding="utf-8")
        self.progress_path.write_text("", encoding="utf-8")
        env = child_environment()
        root = str(Path(__file__).resolve().parents[2])  # the checkout holding generator/ and gendex_envs/
        env["PYTHONPATH"] = os.pathsep.join([root, *[p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p]])
        reaper, pipe = self._start_reaper(env)
        try:
            # Popen forks from this thread, which then watches the child until it has exited: the child's
            # PR_SET_PDEATHSIG fires when the forking *thread* ends, so it must not end first (see probe_child)
            with open(self.log_path, "wb") as logf:
                proc = subprocess.Popen([sys.executable, "-m", "generator.steps.probe_child", str(job_path)],
                                        stdin=subprocess.DEVNULL, stdout=logf, stderr=subprocess.STDOUT, env=env,
                                        start_new_session=True)
            try:
                try:
                    pipe.write(f"{proc.pid}\n")  # start_new_session: its process-group id is its pid
                    pipe.flush()
                except OSError as exc:  # the reaper was killed: PDEATHSIG alone still ends the child with us
                    log.warning("the reward probe's reaper is gone (%s); its folder %s would stay behind if this "
                                "process were killed", exc, self.workdir)
                self._watch(proc)
            finally:
                if proc.poll() is None:
                    self._kill(proc)
        finally:
            self._stop_reaper(reaper, pipe)
        return self.results

    # -------------------------------------------------------------- the reaper (see the module docstring)
    def _start_reaper(self, env: dict) -> tuple[subprocess.Popen, object]:
        read_fd, write_fd = os.pipe()  # not inheritable (PEP 446): only this process holds the write end
        try:
            reaper = subprocess.Popen([sys.executable, "-m", "generator.steps.probe_child", "--reaper",
                                       str(self.workdir)], stdin=read_fd, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL, env=env, start_new_session=True)
        except BaseException:
            os.close(write_fd)
            raise
        finally:
            os.close(read_fd)
        return reaper, os.fdopen(write_fd, "w", encoding="ascii")

    @staticmethod
    def _stop_reaper(reaper: subprocess.Popen, pipe) -> None:
        for tell in (lambda: pipe.write("done\n"), pipe.close):
            try:
                tell()
            except OSError:  # the reaper is gone already (killed by someone): nothing to tell it
                pass
        try:
            reaper.wait(timeout=_REAPER_WAIT_S)
        except subprocess.TimeoutExpired:
            reaper.kill()
            reaper.wait()

    # -------------------------------------------------------------- watching
    def _events(self, offset: int) -> tuple[list[dict], int]:
        with open(self.progress_path, "rb") as f:
            f.seek(offset)
            data = f.read()
        end = data.rfind(b"\n") + 1
        events = [json.loads(line) for line in data[:end].splitlines() if line.strip()]
        return events, offset + end

    def _watch(self, proc: subprocess.Popen) -> None:
        offset = 0
        spawned = time.monotonic()
        while True:
            exited = proc.poll() is not None
            events, offset = self._events(offset)
            for ev in events:
                if self._handle(ev):
                    return
            if exited:
                self._died(proc)
                return
            now = time.monotonic()
            if not self.ready and now - spawned > self.startup_timeout_s:
                self._kill(proc)
                raise GeneratorError(f"the reward probe did not build the env of {self.task_dir} within "
                                     f"{self.startup_timeout_s:g} s; log tail:\n{self._log_tail()}")
            if self.current is not None and now - self.started_at > self.timeout_s:
                self._timed_out(proc)
                return
            self.cpu_seen_s = _cpu_s(proc.pid) or self.cpu_seen_s
            if self.current is not None and self.memory_limit_mb:
                rss = _rss_kb(proc.pid)
                if rss - self.baseline_rss_kb > self.memory_limit_mb * 1024:
                    self._over_memory(proc, rss)
                    return
            time.sleep(_POLL_S)

    def _handle(self, ev: dict) -> bool:
        """Apply one progress event; True when the child is finished."""
        kind = ev.get("ev")
        if kind == "ready":
            self.ready = True
            self.baseline_rss_kb = int(ev.get("rss_kb", 0))
            self.walls = [str(w)[:300] for w in ev.get("walls") or []][:20]
            if ev.get("unconfined"):
                log.warning("reward probe: the child for %s runs the candidates unconfined (%s); walls: %s",
                            self.task_dir, str(ev["unconfined"])[:500], "; ".join(self.walls) or "none")
            else:
                log.info("reward probe: the child for %s is confined in %s ms; walls: %s", self.task_dir,
                         ev.get("confine_ms"), "; ".join(self.walls))
        elif kind == "module":
            self.current = int(ev["i"])
            self.started_at = time.monotonic()
            self.cpu_at_module_s = self.cpu_seen_s
            self.last_call = (None, None)
        elif kind == "call":
            self.last_call = (ev.get("fn"), ev.get("step"))
        elif kind == "result":
            i = int(ev["i"])
            self.results[i] = ProbeReport(**ev["report"]) if ev["ok"] else self._error(i, ev["error"])
            self.current = None
        elif kind == "setup_error":
            raise _setup_error(self.task_dir, ev)
        elif kind == "done":
            return True
        return False

    def _error(self, i: int, record: dict) -> RewardCodeError:
        text = f"{self.displays[i]}: {record['message']}"
        if record.get("kind") == "env":
            return RewardProbeError(text + "\n(the env itself failed; if the reward code is not involved this is a "
                                    "simulator problem)")
        return RewardProbeError(text)

    def _where(self) -> tuple[str, str]:
        """(what was running, when) for the current module, from the last ``call`` event."""
        fn, step = self.last_call
        return (fn, _when(step)) if fn else ("importing the module", "")

    def _timed_out(self, proc: subprocess.Popen) -> None:
        i = self.current
        before = self.log_path.stat().st_size
        try:
            os.kill(proc.pid, signal.SIGUSR1)  # faulthandler dumps every thread's stack to the log
        except ProcessLookupError:
            pass
        deadline = time.monotonic() + _STACK_WAIT_S
        where = ""
        while time.monotonic() < deadline and not where:
            time.sleep(_POLL_S)
            where = _stack_location(self._log_text(before), self.modules[i])
        self._kill(proc)
        what, when = self._where()
        self.results[i] = RewardProbeError(
            f"{self.displays[i]}: {what} did not finish within the time limit of {self.timeout_s:g} s "
            f"{when + ' ' if when else ''}(infinite loop?); it was stopped{where}. Reward functions must return "
            "quickly: batched tensor code, no unbounded loops")

    def _over_memory(self, proc: subprocess.Popen, rss_kb: int) -> None:
        i = self.current
        self._kill(proc)
        what, when = self._where()
        self.results[i] = RewardProbeError(
            f"{self.displays[i]}: {what} grew the probe process by {(rss_kb - self.baseline_rss_kb) // 1024} MB "
            f"{when + ', ' if when else ''}over the {self.memory_limit_mb} MB limit; it was stopped. Reward code "
            "must not accumulate data or allocate large tensors")

    def _over_cpu(self, rc: int) -> bool:
        """Whether the child's own CPU limit ended it: SIGXCPU, or SIGKILL at the hard limit."""
        if rc == -signal.SIGXCPU:
            return True
        budget = self.cpu_module_s if self.current is not None else self.cpu_startup_s
        start = self.cpu_at_module_s if self.current is not None else 0.0
        return rc == -signal.SIGKILL and self.cpu_seen_s - start >= budget - 1

    def _died(self, proc: subprocess.Popen) -> None:
        if self.current is None and not self.ready:
            if self._over_cpu(proc.returncode):
                raise GeneratorError(f"the reward probe process for {self.task_dir} exceeded its CPU budget of "
                                     f"{self.cpu_startup_s} s before the env was built; log tail:\n"
                                     f"{self._log_tail()}")
            raise GeneratorError(f"the reward probe process for {self.task_dir} exited with code {proc.returncode} "
                                 f"before the env was built; log tail:\n{self._log_tail()}")
        if self.current is None:
            if len(self.results) < len(self.modules) and not (
                    self.job["stop_on_error"] and any(isinstance(r, RewardCodeError) for r in self.results.values())):
                raise GeneratorError(f"the reward probe process for {self.task_dir} exited with code "
                                     f"{proc.returncode} between modules; log tail:\n{self._log_tail()}")
            return  # exited after its last result
        i = self.current
        rc = proc.returncode
        where = _stack_location(self._log_text(0), self.modules[i])
        what, when = self._where()
        if self._over_cpu(rc):
            self.results[i] = RewardProbeError(
                f"{self.displays[i]}: the probe process exceeded its CPU budget of {self.cpu_module_s} s while "
                f"{'running ' + what if self.last_call[0] else what}{' ' + when if when else ''} (infinite loop?); "
                f"the kernel stopped it{where}. Reward "
                "functions must return quickly: batched tensor code, no unbounded loops")
            return
        how = f"was killed by {signal.Signals(-rc).name}" if rc < 0 else f"exited with code {rc}"
        self.results[i] = RewardProbeError(
            f"{self.displays[i]}: the probe process {how} while running {what}{' ' + when if when else ''}{where}; "
            f"log tail:\n{self._log_tail()}")

    # -------------------------------------------------------------- process helpers
    @staticmethod
    def _kill(proc: subprocess.Popen) -> None:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
        proc.wait()

    def _log_text(self, offset: int) -> str:
        with open(self.log_path, "rb") as f:
            f.seek(offset)
            return f.read().decode("utf-8", "replace")

    def _log_tail(self, lines: int = 12) -> str:
        return "\n".join(self._log_text(0).splitlines()[-lines:])


class _TerminateAsExit:
    """While a probe runs in the main thread, ``SIGTERM`` raises :class:`SystemExit` so that ``finally`` blocks run.

    Only where ``SIGTERM`` still has its default action (an application's own handler is left alone); the previous
    handler is restored afterwards. Elsewhere the reaper and the child's ``PDEATHSIG`` clean up after the parent.
    """

    def __enter__(self):
        self.previous = None
        if threading.current_thread() is threading.main_thread() and \
                signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:
            self.previous = signal.signal(signal.SIGTERM, self._raise)
        return self

    def __exit__(self, *exc) -> None:
        if self.previous is not None:
            signal.signal(signal.SIGTERM, self.previous)

    @staticmethod
    def _raise(signum, _frame) -> None:
        log.warning("the reward probe got SIGTERM: stopping its child and removing its temporary folder")
        raise SystemExit(128 + signum)


def probe_modules(task_dir: Path, modules: list[Path], *, steps: int, timeout_s: float, seed: int, num_envs: int,
           sim_backend: str, memory_limit_mb: int | None, startup_timeout_s: float,
           stop_on_error: bool, module_cpu_s: float | None = None,
           check_static: bool = True) -> list[ProbeReport | RewardCodeError | None]:
    """Probe ``modules`` in as few processes as possible (a new one only after a module was killed).

    The child loads every module as untrusted: statically checked again (unless ``check_static`` is False) and run
    under the runtime guard (:mod:`gendex_envs.guard`), whichever folder it is in, behind the kernel walls the child
    raises around itself first (:func:`generator.steps.probe_child._confine`).

    Returns one entry per module: its report, its error, or None when ``stop_on_error`` left it unprobed.
    ``module_cpu_s`` is the CPU time a module may use before the child's own limit ends it (default
    ``CPU_MARGIN * timeout_s + CPU_SLACK_S``: a backstop behind the parent's wall-clock limit).
    """
    if not TaskLayout(task_dir).spec.is_file():
        raise TaskNotFoundError(f"{task_dir} holds no task spec ({TaskLayout(task_dir).spec.name})")
    for m in modules:
        if not m.is_file():
            raise FileNotFoundError(f"reward module {m} does not exist")
    displays = [module_display(task_dir, m) for m in modules]
    results: list[ProbeReport | RewardCodeError | None] = [None] * len(modules)
    start = 0
    while start < len(modules):
        with _TerminateAsExit(), tempfile.TemporaryDirectory(prefix="gendex_probe_") as tmp:
            child = _Child(task_dir, modules[start:], displays[start:], steps=steps, timeout_s=timeout_s, seed=seed,
                           num_envs=num_envs, sim_backend=sim_backend, memory_limit_mb=memory_limit_mb,
                           startup_timeout_s=startup_timeout_s, stop_on_error=stop_on_error, workdir=Path(tmp),
                           module_cpu_s=module_cpu_s, check_static=check_static)
            got = child.run()
        for i, r in got.items():
            results[start + i] = r
        if stop_on_error and any(isinstance(r, RewardCodeError) for r in got.values()):
            break
        done = max(got) + 1 if got else len(modules) - start
        start += done
    for m, r in zip(displays, results, strict=True):
        if isinstance(r, ProbeReport):
            log.info("probe %s: ok, reward %.3g..%.3g, success %.2f, %.1f s%s", m, r.reward_min, r.reward_max,
                     r.success_rate, r.wall_s, f", warnings: {r.warnings}" if r.warnings else "")
        elif r is not None:
            log.info("probe %s: rejected: %s", m, r)
    return results


def probe_task(task_dir: str | Path, modules: list[str | Path], *, steps: int = DEFAULT_STEPS,
               timeout_s: float = DEFAULT_TIMEOUT_S, seed: int = 0, num_envs: int = 1,
               sim_backend: str = "physx_cpu", memory_limit_mb: int | None = DEFAULT_MEMORY_LIMIT_MB,
               startup_timeout_s: float = DEFAULT_STARTUP_TIMEOUT_S, check_static: bool = True,
               module_cpu_s: float | None = None) -> list[ProbeReport]:
    """Probe several reward modules of one task in one child process; raises for the first bad module.

    Each module gets ``timeout_s`` seconds (import, reset and ``steps`` seeded random-action steps); building the
    env is not charged to it (``startup_timeout_s``). ``check_static`` runs :func:`check_reward_file` on each module
    first (on by default: the probe never executes code that did not pass it unless asked to). Raises
    :class:`~generator.errors.RewardProbeError` (or the static check's error) whose message starts with the
    module's path relative to ``task_dir``. ``module_cpu_s``: see :func:`probe_modules`.
    """
    task_dir = Path(task_dir)
    paths = [Path(m) for m in modules]
    if check_static:
        for p in paths:
            check_reward_file(p, module_display(task_dir, p))
    results = probe_modules(task_dir, paths, steps=steps, timeout_s=timeout_s, seed=seed, num_envs=num_envs,
                     sim_backend=sim_backend, memory_limit_mb=memory_limit_mb, startup_timeout_s=startup_timeout_s,
                     stop_on_error=True, module_cpu_s=module_cpu_s, check_static=check_static)
    for r in results:
        if isinstance(r, RewardCodeError):
            raise r
    return [r for r in results if isinstance(r, ProbeReport)]


def probe_reward_module(task_dir: str | Path, module_path: str | Path, *, steps: int = DEFAULT_STEPS,
                        timeout_s: float = DEFAULT_TIMEOUT_S, seed: int = 0, **kwargs) -> ProbeReport:
    """:func:`probe_task` for one module."""
    return probe_task(task_dir, [module_path], steps=steps, timeout_s=timeout_s, seed=seed, **kwargs)[0]
