"""Child process of the reward probe (internal to :mod:`generator.steps.probe`).

``python -m generator.steps.probe_child JOB.json`` builds the task's env once, then for each candidate reward module
swaps it in (wrapped so that every call is checked), resets with the job's seed and steps seeded random actions.
It reports JSON lines to the job's ``progress`` file, one object per line (``ev`` says which):

* ``{"ev": "ready", "rss_kb": int, "cpu_s": float, "walls": [str], "unconfined": str | None, "confine_ms": float}``:
  the env is built and the kernel walls are up (``walls``; ``unconfined`` says why not, under an opt-out).
* ``{"ev": "module", "i": int}``: module ``i`` starts (the parent's per-module time limit starts here).
* ``{"ev": "call", "i": int, "fn": str, "step": int}``: a reward function is about to run (step 0 is the reset).
* ``{"ev": "result", "i": int, "ok": true, "report": {...}}`` or ``{..., "ok": false, "error": {...}}`` where
  ``error`` is ``{"kind", "fn", "step", "message"}``; ``kind`` is ``violation`` (wrong output), ``exception``,
  ``import``, ``audit`` (file/process/network access) or ``env`` (the env failed outside reward code).
* ``{"ev": "setup_error", "type": str, "message": str}``: the env could not be built, or (``RewardSandboxError``)
  this system cannot confine this process and no opt-out is set (:data:`OPT_OUT_ENVS`).
* ``{"ev": "done"}``.

The checks are batched tensor operations (no per-env Python loops), so they work on the GPU backend as well.
The parent enforces the wall-clock and memory limits: it kills this process group; ``SIGUSR1`` makes
:mod:`faulthandler` dump the stack first, so the parent can name the line that hung.

Process hygiene does not depend on the parent staying alive or responsive (see :mod:`generator.steps.probe`):

* before anything else this process asks the kernel for ``SIGKILL`` when its parent dies (``PR_SET_PDEATHSIG``,
  Linux; a thread polling :func:`os.getppid` elsewhere), then checks the parent is still the one in the job;
* it limits its own CPU time (``RLIMIT_CPU``; the job's budgets): a hung module gets ``SIGXCPU`` (stack dumped,
  then the default action ends the process) even when nobody watches it; no core files (``RLIMIT_CORE`` 0) and
  no file larger than the job's ``max_file_mb`` (``RLIMIT_FSIZE``);
* once the env is built, before the first candidate is read, it raises the kernel walls of the sandbox's worker
  around itself (:func:`_confine`: no privileges, Landlock, seccomp), and refuses to run candidates where it
  cannot (``docs/security.md``, Isolation);
* ``python -m generator.steps.probe_child --reaper WORKDIR`` is the reaper the parent starts next to each child: it
  reads child process-group ids from stdin, a pipe whose write end only the parent holds, and exits at ``done``;
  at end of file without ``done`` the parent died, so it kills the groups and removes ``WORKDIR``.
"""

from __future__ import annotations

import faulthandler
import json
import logging
import math
import os
import resource
import shutil
import signal
import sys
import threading
import time
import traceback
import warnings
from pathlib import Path
from typing import ClassVar

log = logging.getLogger(__name__)

EXCEPTION_TEXT_LIMIT = 600
ORPHANED_EXIT = 70
"""Exit status when the parent was already gone at start (or, without prctl, died later)."""
_PR_SET_PDEATHSIG = 1
_PARENT_POLL_S = 0.5
_CPU_GRACE_S = 5
"""Seconds between ``SIGXCPU`` (soft limit) and the kernel's ``SIGKILL`` (hard limit)."""
_REAP_WAIT_S = 3.0
_BLOCKED_EVENT_PREFIXES = (
    "open", "os.", "subprocess.", "socket.", "shutil.", "ctypes.", "builtins.input", "pty.", "urllib.",
    "webbrowser.", "glob.", "tempfile.", "sys.addaudithook", "marshal.", "pickle.", "winreg.", "msvcrt.", "sqlite3.",
    "ftplib.", "smtplib.", "poplib.", "imaplib.", "nntplib.", "telnetlib.", "http.client.",
)
"""Audit events refused while reward code runs (a second fence behind the static check; PEP 578 hooks)."""


class _Audit:
    """Refuses file, process and network events while ``active``; remembers the first one for the report."""

    active: ClassVar[bool] = False
    events: ClassVar[list[str]] = []

    @classmethod
    def hook(cls, event: str, args: tuple) -> None:
        if not cls.active or not event.startswith(_BLOCKED_EVENT_PREFIXES):
            return
        detail = ", ".join(repr(a)[:80] for a in args[:2])
        cls.events.append(f"{event}({detail})")
        raise PermissionError(f"blocked by the reward probe: {event}")


class _Violation(Exception):
    """A reward function broke the interface; carries the JSON error record."""

    def __init__(self, kind: str, fn: str | None, step: int, message: str):
        super().__init__(message)
        self.record = {"kind": kind, "fn": fn, "step": step, "message": message}


def _when(step: int) -> str:
    return "right after reset (step 0)" if step == 0 else f"at step {step}"


def _exception_text(exc: BaseException, module_path: Path, fn: str | None = None) -> str:
    """``Type: message at line N (`code`)``; the line is the deepest frame inside the reward module."""
    text = f"{type(exc).__name__}: {exc}".strip()
    if len(text) > EXCEPTION_TEXT_LIMIT:
        text = text[: EXCEPTION_TEXT_LIMIT - 3] + "..."
    frames = [f for f in traceback.extract_tb(exc.__traceback__) if Path(f.filename).resolve() == module_path]
    if frames:
        f = frames[-1]
        code = f" (`{f.line.strip()}`)" if f.line and f.line.strip() else ""
        text += f" at line {f.lineno}{code}" + (f" in {f.name}" if f.name != fn else "")
    return text


class _CheckedModule:
    """Wraps one reward module: runs each function under the audit hook and checks what it returns."""

    def __init__(self, env, module, progress, index: int):
        import torch

        self.torch = torch
        self.env = env
        self.module = module
        self.progress = progress
        self.index = index
        self.n = env.num_envs
        self.device = torch.device(env.device)
        self.step = 0
        self.rewards: list = []
        self.successes: list = []
        self.fails: list = []
        self.obs_shapes: dict[str, tuple[int, ...]] = {}
        self.reserved_obs_keys: frozenset[str] = frozenset()
        self.warnings: list[str] = []

    # -------------------------------------------------------------- running untrusted calls
    def call(self, fn_name: str, fn, *args):
        self.progress.emit(ev="call", i=self.index, fn=fn_name, step=self.step)
        _Audit.events.clear()
        with warnings.catch_warnings(record=True) as caught:  # no linecache file reads for warnings
            warnings.simplefilter("always")
            _Audit.active = True
            try:
                out = fn(*args)
            except BaseException as exc:
                _Audit.active = False
                if _Audit.events:
                    raise self._audit_violation(fn_name) from None
                raise _Violation("exception", fn_name, self.step,
                                 f"{_when(self.step)}, {fn_name} raised "
                                 f"{_exception_text(exc, self.module.path, fn_name)}") from None
            finally:
                _Audit.active = False
        if _Audit.events:
            raise self._audit_violation(fn_name)
        for w in caught:
            text = f"{fn_name} warned {_when(self.step)}: {w.category.__name__}: {w.message}"
            if text not in self.warnings and len(self.warnings) < 10:
                self.warnings.append(text)
        return out

    def _audit_violation(self, fn_name: str) -> _Violation:
        return _Violation("audit", fn_name, self.step,
                          f"{_when(self.step)}, {fn_name} tried to reach outside the simulator "
                          f"({_Audit.events[0]}); reward code may not touch files, processes or the network")

    def fail(self, fn_name: str, message: str) -> _Violation:
        return _Violation("violation", fn_name, self.step, f"{_when(self.step)}, {fn_name} {message}")

    # -------------------------------------------------------------- checks
    # The rules on what each function returns are the env's own (gendex_envs.reward_checks, applied on every call
    # of every env); here their RewardOutputError becomes the probe's violation record. The probe adds two rules of
    # its own: generated modules return 'fail', and observation shapes stay the same from step to step.
    def _checked(self, fn: str, check, *args, **kwargs):
        from gendex_envs.reward_checks import RewardOutputError

        try:
            return check(*args, self.n, self.device, path=self.module.path, step=self.step, **kwargs)
        except RewardOutputError as exc:
            raise self.fail(fn, exc.problem) from None

    def evaluate(self, env) -> dict:
        from gendex_envs.reward_checks import check_evaluate

        info = self._checked("evaluate", check_evaluate, self.call("evaluate", self.module.evaluate, env))
        if "fail" not in info:
            raise self.fail("evaluate", f"returned keys {sorted(info)} without 'fail'; generated reward modules "
                            "must return 'fail' as a [num_envs] bool tensor (all False when nothing counts as "
                            "failure, e.g. `torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)`)")
        return info

    def compute_dense_reward(self, env, obs, action, info):
        from gendex_envs.reward_checks import check_reward

        self.successes.append(info["success"].detach().clone())  # as the env decided it (conditions, fail)
        self.fails.append(info["fail"].detach().clone())
        reward = self._checked("compute_dense_reward", check_reward,
                               self.call("compute_dense_reward", self.module.compute_dense_reward, env, obs, action,
                                         info))
        self.rewards.append(reward.detach().float().clone())
        return reward

    def get_obs_extra(self, env, info) -> dict:
        from gendex_envs.reward_checks import check_obs_extra

        fn = "_get_obs_extra"
        extra = self._checked(fn, check_obs_extra, self.call(fn, self.module.get_obs_extra, env, info),
                              taken=self.reserved_obs_keys)
        for key, value in extra.items():
            shape = tuple(value.shape)
            first = self.obs_shapes.setdefault(key, shape)
            if first != shape:
                raise self.fail(fn, f"returned {key!r} with shape {shape}, but it had shape {first} before; "
                                "observation shapes must not change between steps")
        missing = sorted(set(self.obs_shapes) - set(extra))
        if missing:
            raise self.fail(fn, f"stopped returning the keys {missing}; every step must return the same keys")
        return extra

    # -------------------------------------------------------------- summary
    def report(self, display: str, wall_s: float) -> dict:
        torch = self.torch
        rewards = torch.cat(self.rewards) if self.rewards else torch.zeros(0)
        successes = torch.stack(self.successes).float() if self.successes else torch.zeros(0)
        fails = torch.stack(self.fails).float() if self.fails else torch.zeros(0)
        warns = list(self.warnings)
        if rewards.numel():
            r_max = float(rewards.max())
            if r_max > self.module.reward_max * (1 + 1e-5):
                warns.append(f"compute_dense_reward returned {r_max:.4g} > REWARD_MAX={self.module.reward_max:g}; "
                             "the normalised reward will exceed 1")
            if rewards.numel() > 1 and float(rewards.max() - rewards.min()) == 0.0:
                warns.append(f"compute_dense_reward returned the same value ({r_max:.4g}) at every step: no "
                             "learning signal under random actions")
        if successes.numel() and bool(successes[0].all()):
            warns.append("success is already True at the first step")
        if fails.numel() and bool(fails[0].all()):
            warns.append("fail is already True at the first step: every episode would end at once")
        return {
            "module": display,
            "path": str(self.module.path),
            "steps": self.step,
            "num_envs": self.n,
            "reward_min": float(rewards.min()) if rewards.numel() else math.nan,
            "reward_max": float(rewards.max()) if rewards.numel() else math.nan,
            "reward_mean": float(rewards.mean()) if rewards.numel() else math.nan,
            "success_rate": float(successes.mean()) if successes.numel() else 0.0,
            "fail_rate": float(fails.mean()) if fails.numel() else 0.0,
            "obs_extra": {k: list(v[1:]) for k, v in self.obs_shapes.items()},
            "wall_s": round(wall_s, 3),
            "warnings": warns,
        }


# ------------------------------------------------------------------ process hygiene
def _die_with_parent(parent_pid: int | None) -> str:
    """Make this process die with its parent; returns how (``prctl`` or ``thread``).

    Runs first in :func:`main`, before the audit hook (which refuses ``ctypes`` events) and before any untrusted code.
    ``PR_SET_PDEATHSIG`` fires when the *thread* that forked this process exits, not the whole parent process: the
    parent calls ``Popen`` from the thread that then watches this child until it has exited (``probe._Child.run``),
    so that thread outlives the child unless the parent process itself dies, which is the case this is meant for.
    The signal is ``SIGKILL`` because a stuck child (a loop holding the GIL, a hang inside C code) runs no handler.
    """
    how = "thread"
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            if libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) != 0:
                raise OSError(ctypes.get_errno(), "prctl(PR_SET_PDEATHSIG) failed")
            how = "prctl"
        except (OSError, AttributeError) as exc:
            log.warning("the reward probe child cannot ask for SIGKILL at its parent's death (%s); polling instead",
                        exc)
    # the parent may have died before prctl took effect: then this process was already re-parented
    if parent_pid is not None and os.getppid() != parent_pid:
        os._exit(ORPHANED_EXIT)
    if how == "thread" and parent_pid is not None:
        threading.Thread(target=_poll_parent, args=(parent_pid,), name="probe-parent-watch", daemon=True).start()
    return how


def _poll_parent(parent_pid: int) -> None:
    """Portable fallback: exit as soon as the parent is gone (a Python loop in reward code still yields the GIL)."""
    while os.getppid() == parent_pid:
        time.sleep(_PARENT_POLL_S)
    os._exit(ORPHANED_EXIT)  # os._exit raises no audit event, so the hook cannot refuse it


def _cpu_used_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def _set_cpu_limit(soft_s: float, hard_s: float | None = None) -> None:
    """``RLIMIT_CPU``: ``SIGXCPU`` at ``soft_s`` CPU seconds (this process, all threads), ``SIGKILL`` at the hard."""
    _soft, hard = resource.getrlimit(resource.RLIMIT_CPU)
    if hard_s is not None:
        hard = math.ceil(hard_s) if hard == resource.RLIM_INFINITY else min(math.ceil(hard_s), hard)
    soft = math.ceil(soft_s)
    if hard != resource.RLIM_INFINITY:
        soft = min(soft, max(hard - _CPU_GRACE_S, 1))
    resource.setrlimit(resource.RLIMIT_CPU, (soft, hard))


def _limit_startup(job: dict) -> None:
    """Limits set before the simulator is imported: CPU for the whole run (hard) and for building the env (soft)."""
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))  # SIGXCPU's default action would dump core into the cwd
    # SIGXCPU: dump the stack (the parent names the line), then chain to the default action, which ends the process
    faulthandler.register(signal.SIGXCPU, file=sys.stderr, all_threads=True, chain=True)
    startup = job.get("cpu_startup_s")
    module = job.get("cpu_module_s")
    if startup and module:
        total = float(startup) + len(job["modules"]) * float(module) + _CPU_GRACE_S
        _set_cpu_limit(float(startup), total)


def _limit_before_untrusted_code(job: dict) -> None:
    """Limits set once the env is built, before the first candidate module is imported.

    Not set: ``RLIMIT_AS`` (torch, SAPIEN and the CUDA runtime reserve far more virtual address space than they use,
    so an address-space cap breaks them; ``RLIMIT_DATA`` bounds heap growth instead, see :func:`main`) and
    ``RLIMIT_NPROC`` (it counts every process and thread of the user, machine-wide, so any useful value would break
    thread pools and other work of the same user; spawning is refused by the audit hook and the seccomp filter
    instead).
    """
    max_file_mb = job.get("max_file_mb")
    if max_file_mb:
        limit = int(max_file_mb) * 1024 * 1024
        _soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit if hard == resource.RLIM_INFINITY else min(limit, hard),
                                                   hard))


def _limit_module_cpu(job: dict) -> None:
    """Before each module: ``cpu_module_s`` more CPU seconds from now (never past the hard limit)."""
    module = job.get("cpu_module_s")
    if module:
        _set_cpu_limit(_cpu_used_s() + float(module))


# ------------------------------------------------------------------ kernel walls
OPT_OUT_ENVS = ("GENDEX_IN_PROCESS_GUARD", "GENDEX_TRUST_REMOTE_CODE")
"""Either set to 1 in the parent's environment lets the candidates run unconfined where this system cannot confine
this process: the opt-outs of the sandbox's worker (the runtime guard alone; all code trusted). Without one such a
system refuses to probe."""


def _opted_out() -> str | None:
    """The first :data:`OPT_OUT_ENVS` variable set (read before :func:`main` sets its own guard variable)."""
    for name in OPT_OUT_ENVS:
        if os.environ.get(name, "").strip().lower() in ("1", "true", "yes"):
            return name
    return None


def _unconfinable(exc: Exception) -> str:
    return (f"the reward probe runs model-written reward code only in a confined child process, and this system "
            f"cannot confine one: {exc}. GENDEX_IN_PROCESS_GUARD=1 probes the candidates under the weaker runtime "
            f"guard only; GENDEX_TRUST_REMOTE_CODE=1 trusts all code")


def _confinement_tools():
    """``(pyseccomp, Landlock ABI)``, loaded before the env is built, so that a system that cannot confine fails at
    once (and finding libseccomp runs ``ldconfig``, which the walls refuse). Raises
    :class:`~gendex_envs.sandbox.confine.ConfinementError` naming what is missing."""
    from gendex_envs.sandbox import confine

    if not sys.platform.startswith("linux"):
        raise confine.ConfinementError(f"Landlock and seccomp are Linux's; this is {sys.platform}")
    sc = confine.load_seccomp()
    abi = confine.landlock_abi()
    if abi < 1:
        raise confine.ConfinementError("Landlock is not available (Linux >= 5.13 with Landlock enabled is needed)")
    return sc, abi


def _candidate_files(job: dict) -> list[str]:
    """The candidates' files as :func:`~gendex_envs.reward_module.load_reward_module` names them (folder resolved,
    the name not followed); links are left out: that loader refuses them, and a rule would open their target."""
    files = []
    for module in job["modules"]:
        named = Path(module).absolute()
        path = named.parent.resolve() / named.name
        if path.is_file() and not path.is_symlink():
            files.append(str(path))
    return files


def _confine(job: dict, tools, walls: list[str]) -> None:
    """Raise the kernel walls of the sandbox's worker (:mod:`gendex_envs.sandbox.confine`) around this process, once
    the env is built and before any candidate is read, appending each to ``walls``; irreversible.

    * not dumpable, no new privileges, no capabilities (a child of root keeps uid 0 but none of its powers);
    * Landlock: read files only under :func:`~gendex_envs.sandbox.confine.readable_roots` (the Python installation,
      the system libraries), the ``gendex_envs`` package (what candidates import from it, ``reward_terms``, and the
      source lines of tracebacks) and the candidate module files themselves (not their folders); write, create,
      delete or execute nothing anywhere; no TCP bind or connect (ABI >= 4), no signals out, no abstract unix
      sockets (ABI >= 6). Landlock judges a file when it is opened: the progress file and the log, opened before,
      stay writable;
    * seccomp: the worker's filter (no exec, fork, sockets, ptrace...; threads stay allowed), except that this
      process may still move its own ``RLIMIT_CPU`` soft limit (:func:`_limit_module_cpu`, within the hard limit).

    Not the worker's rlimits: this process keeps its own (its CPU budgets, ``RLIMIT_FSIZE`` for its progress file,
    ``RLIMIT_DATA``).
    """
    from gendex_envs.sandbox import confine

    sc, abi = tools
    confine.not_dumpable()
    walls.append("not dumpable")
    candidates = _candidate_files(job)
    package = str(Path(confine.__file__).resolve().parents[1])  # gendex_envs/
    landlock = confine.landlock([*confine.readable_roots(), package, *candidates], abi)  # sets no_new_privs first
    walls.append("no new privileges")
    walls.append(f"landlock: files read-only under the Python installation, the system libraries, the gendex_envs "
                 f"package and the {len(candidates)} candidate module files; no write anywhere (the progress file "
                 f"was opened before)")
    walls += landlock[1:]
    if os.geteuid() == 0 or os.getuid() == 0:
        confine.drop_capabilities()  # before the filter, which denies capset
        walls.append("capabilities: none")
    confine.seccomp(sc, settable_limit=resource.RLIMIT_CPU)
    walls.append("seccomp: no exec, fork, sockets, ptrace, mounts, bpf, keys, signals to others or new limits "
                 "(but its own CPU soft limit)")


def reap(workdir: str, stream=None) -> int:
    """The reaper: wait for the parent's ``done``; if the pipe closes without it, kill the children, remove ``workdir``.

    Reads lines from ``stream`` (stdin): a process-group id per child the parent started, ``done`` when the parent
    cleaned up itself. Only the parent holds the pipe's write end (pipes are not inherited across ``exec``), so end
    of file without ``done`` means the parent died, however it died (``SIGKILL`` included). Imports nothing heavy.
    """
    stream = stream if stream is not None else sys.stdin
    for sig in (signal.SIGINT, signal.SIGHUP):  # a terminal's Ctrl-C or hang-up goes to the parent, which cleans up
        signal.signal(sig, signal.SIG_IGN)
    groups: list[int] = []
    for line in stream:
        word = line.strip()
        if word == "done":
            return 0
        if word.isdigit():
            groups.append(int(word))
    for pgid in groups:
        try:
            os.killpg(pgid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
    deadline = time.monotonic() + _REAP_WAIT_S
    while True:  # a dying child may still hold files open; retry until the folder is gone
        shutil.rmtree(workdir, ignore_errors=True)
        if not os.path.exists(workdir) or time.monotonic() > deadline:
            break
        time.sleep(0.05)
    return 1


class _Progress:
    """The JSON-lines progress file; opened before the kernel walls, which refuse every later open for writing."""

    def __init__(self, path: str):
        self.f = open(path, "a", buffering=1, encoding="utf-8")

    def emit(self, **record) -> None:
        self.f.write(json.dumps(record, default=str) + "\n")
        self.f.flush()


def _vm_kb(field: str) -> int:
    with open("/proc/self/status", encoding="ascii") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    return 0


def _probe_module(env, job: dict, index: int, progress: _Progress) -> dict:
    """Probe one module; returns the result record."""
    import torch

    from gendex_envs import guard
    from gendex_envs.reward_module import RewardModule, load_reward_module
    from gendex_envs.spec import resolve_stage
    from gendex_envs.success import Judge

    path = Path(job["modules"][index]).resolve()
    display = job["displays"][index]
    t0 = time.monotonic()
    progress.emit(ev="module", i=index)
    try:
        # model code, wherever its folder is: statically checked (unless the job says not to) and guarded, unless
        # the user trusts all code (GENDEX_TRUST_REMOTE_CODE=1); this process's own audit fence applies either way
        module = load_reward_module(path, trusted=guard.trusts_everything(),
                                    static_check=job.get("check_static", True) and not _first_wall_down(job))
    except Exception as exc:
        cause = exc.__cause__ or exc
        text = _exception_text(cause, path) if exc.__cause__ else f"{type(exc).__name__}: {exc}"
        return {"ev": "result", "i": index, "ok": False,
                "error": {"kind": "import", "fn": None, "step": 0, "message": f"importing it failed: {text}"}}
    checked = _CheckedModule(env, module, progress, index)
    checked.reserved_obs_keys = job["_reserved_obs_keys"]
    wrapped = RewardModule(path=module.path, evaluate=checked.evaluate,
                           compute_dense_reward=checked.compute_dense_reward,
                           get_obs_extra=checked.get_obs_extra if module.get_obs_extra else None,
                           reward_max=module.reward_max)
    stage = job["stages"][index]
    spec = env.task_spec
    # judged as the env will judge it: a stage module by its stage's conditions, the task's by the task's
    if stage is not None and stage in {s.name for s in spec.stages}:
        env.judge = Judge.of_stage(spec, resolve_stage(spec, stage)[1], wrapped)
    else:
        env.judge = Judge.of_task(spec, wrapped)
    gen = torch.Generator().manual_seed(job["seed"])
    try:
        env.reset(seed=job["seed"])
        low = torch.as_tensor(env.action_space.low, dtype=torch.float32)
        high = torch.as_tensor(env.action_space.high, dtype=torch.float32)
        for step in range(1, job["steps"] + 1):
            checked.step = step
            action = low + (high - low) * torch.rand(low.shape, generator=gen)
            env.step(action.to(env.device))
    except _Violation as v:
        return {"ev": "result", "i": index, "ok": False, "error": v.record}
    except Exception as exc:
        tb = "".join(traceback.format_exception(exc, limit=-4)).strip()
        return {"ev": "result", "i": index, "ok": False,
                "error": {"kind": "env", "fn": None, "step": checked.step,
                          "message": f"{_when(checked.step)}, the env failed outside the reward functions: "
                                     f"{type(exc).__name__}: {exc}\n{tb}"}}
    finally:
        env.judge = job["_default_judge"]
    return {"ev": "result", "i": index, "ok": True, "report": checked.report(display, time.monotonic() - t0)}


def _first_wall_down(job: dict) -> bool:
    """Tests only (:data:`generator.steps.probe.FIRST_WALL_DOWN_FOR_TESTS`, set in the parent's process): load the
    candidates as if the first wall had a hole, to test the kernel's walls behind it."""
    return job.get("first_wall_down_for_tests") is True


def _take_first_wall_down() -> None:
    """No restricted builtins and no runtime guard's audit hook for the candidates (the probe's own hook is not
    installed either: :func:`main`)."""
    import builtins

    from gendex_envs import guard

    guard.restricted_builtins = lambda: dict(vars(builtins))
    guard.untrust = lambda folder: None


def main(argv: list[str]) -> int:
    if argv[:1] == ["--reaper"]:
        return reap(argv[1])
    job = json.loads(Path(argv[0]).read_text(encoding="utf-8"))
    _die_with_parent(job.get("parent_pid"))  # first: before any simulator, reward code or audit hook
    opted_out = _opted_out()  # the parent's environment, before the next line sets this process's own
    # this process is the probe's own boundary (its CPU budgets, memory and file limits, audit hook, reaper): the
    # candidates run here, in-process, so that those budgets measure them (not gendex_envs.sandbox's worker)
    os.environ["GENDEX_IN_PROCESS_GUARD"] = "1"
    faulthandler.enable(file=sys.stderr, all_threads=True)
    faulthandler.register(signal.SIGUSR1, file=sys.stderr, all_threads=True)
    _limit_startup(job)
    progress = _Progress(job["progress"])
    logging.basicConfig(level=logging.WARNING, stream=sys.stderr)
    unconfined = None
    try:
        tools = _confinement_tools()
    except Exception as exc:  # ConfinementError; anything else a broken libseccomp raises, too
        if opted_out is None:
            progress.emit(ev="setup_error", type="RewardSandboxError", message=_unconfinable(exc))
            return 2
        tools, unconfined = None, f"{opted_out}=1 and this system cannot confine it: {exc}"
    try:
        import torch

        from gendex_envs.assets.catalog import asset_ids
        from gendex_envs.spec import load_task_spec
        from gendex_envs.task_env import TaskEnv

        torch.set_num_threads(1)
        spec = load_task_spec(job["spec"], known_assets=asset_ids())
        # built with the default reward module (in-memory spec): candidates are swapped in one after the other
        env = TaskEnv(task_spec=spec, num_envs=job["num_envs"], obs_mode="state", reward_mode="dense",
                      sim_backend=job["sim_backend"], render_backend="none")
        env.reset(seed=job["seed"])
        job["_default_judge"] = env.judge
        job["_reserved_obs_keys"] = env.own_obs_keys()
    except Exception as exc:
        progress.emit(ev="setup_error", type=type(exc).__name__, message=str(exc),
                      traceback="".join(traceback.format_exception(exc, limit=-6)))
        return 2
    if env.device.type == "cpu" and job.get("memory_limit_mb"):
        # allocations beyond the budget fail inside the reward code (MemoryError / torch RuntimeError with a line)
        limit = (_vm_kb("VmData") + int(job["memory_limit_mb"]) * 1024) * 1024
        _soft, hard = resource.getrlimit(resource.RLIMIT_DATA)
        resource.setrlimit(resource.RLIMIT_DATA, (limit if hard == resource.RLIM_INFINITY else min(limit, hard),
                                                  hard))
    _limit_before_untrusted_code(job)
    rss_kb = _vm_kb("VmRSS")  # /proc: read before the walls
    walls: list[str] = []
    t0 = time.perf_counter()
    if tools is not None:
        try:
            _confine(job, tools, walls)
        except Exception as exc:  # ConfinementError: a wall the kernel refused; the earlier ones stay up
            if opted_out is None:
                progress.emit(ev="setup_error", type="RewardSandboxError", message=_unconfinable(exc))
                return 2
            unconfined = f"{opted_out}=1 and this system cannot confine it: {exc}"
    confine_ms = round((time.perf_counter() - t0) * 1000, 1)
    if unconfined:
        log.warning("the reward probe's child runs the candidates unconfined (%s); walls: %s", unconfined,
                    "; ".join(walls) or "none")
    if _first_wall_down(job):
        _take_first_wall_down()
    else:
        sys.addaudithook(_Audit.hook)
    progress.emit(ev="ready", rss_kb=rss_kb, cpu_s=round(_cpu_used_s(), 3), walls=walls, unconfined=unconfined,
                  confine_ms=confine_ms)
    for index in range(len(job["modules"])):
        _limit_module_cpu(job)
        result = _probe_module(env, job, index, progress)
        progress.emit(**result)
        if not result["ok"] and job.get("stop_on_error"):
            break
    env.close()
    progress.emit(ev="done")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
