"""The parent's side of the sandbox: one confined worker process per parent process, modules loaded into it,
calls with a snapshot of the env members each function reads (see :mod:`gendex_envs.sandbox`)."""

from __future__ import annotations

import atexit
import builtins
import logging
import math
import os
import queue
import select
import signal
import subprocess
import sys
import threading
import time
import weakref
from pathlib import Path

import torch

from gendex_envs.errors import GenDexError, RewardModuleError, RewardSandboxError, RewardTimeoutError
from gendex_envs.sandbox import confine, protocol, replay

log = logging.getLogger(__name__)

CALL_TIMEOUT_S = 5.0
"""Wall-clock limit of one reward call in the worker (a committed module's call takes 0.1-0.5 ms)."""
TIMEOUT_ENV = "GENDEX_SANDBOX_TIMEOUT_S"
"""Raises (or lowers) :data:`CALL_TIMEOUT_S`."""
START_TIMEOUT_S = 120.0
"""Limit for starting a worker (importing torch takes about 2 s on an idle machine)."""
MEMORY_ENV = "GENDEX_SANDBOX_MEMORY_MB"
"""Raises (or lowers) the worker's address-space limit, :data:`gendex_envs.sandbox.confine.MEMORY_LIMIT_BYTES`."""
CPU_ENV = "GENDEX_SANDBOX_CPU_S"
"""Raises (or lowers) the worker's total CPU-time limit, :data:`gendex_envs.sandbox.confine.CPU_LIMIT_S`."""
IN_PROCESS_ENV = "GENDEX_IN_PROCESS_GUARD"
"""Set to 1 to run untrusted reward modules in this process under the runtime guard only (the first wall), e.g.
on a system without Landlock or seccomp; without it such a system refuses untrusted modules."""
WORKER = Path(__file__).resolve().with_name("worker.py")
FULL_BUILTINS_FOR_TESTS = False
"""Tests only: load modules in the worker with Python's ordinary builtins, as if the first wall had a hole."""
MAX_KEY_ARG_CHARS = 4096
FUNCTIONS = ("evaluate", "compute_dense_reward", "_get_obs_extra")
ARITY = {"evaluate": 0, "_get_obs_extra": 1, "compute_dense_reward": 3}
REPLAY_ENV = "GENDEX_SANDBOX_REPLAY"
"""Set to 0 to serve every call of untrusted reward code from the worker (no in-process replay of recorded calls)."""
MAX_TRACES = 8
"""Recordings one function of one module may ask of the worker (a function whose calls keep coming out otherwise
than recorded, a branch on data, stays with the worker after these)."""
MAX_VARIANTS = 4
"""Graphs kept per function and argument signature (one per outcome of the guards that differ)."""
REPLAY_SLOW_S = 0.25
"""A replay that takes longer than this ends replays of the module (committed modules replay in 0.05-0.3 ms)."""
AUDIT_AT = (16, 64, 256)
AUDIT_EVERY = 1024
"""The replays of a function also asked of the worker and compared (the :data:`AUDIT_AT`-th, then every
:data:`AUDIT_EVERY`-th); a difference ends replays of the module."""


def enabled() -> bool:
    """Whether untrusted reward modules go to the worker (unless :data:`IN_PROCESS_ENV` opts out)."""
    return os.environ.get(IN_PROCESS_ENV, "").strip().lower() not in ("1", "true", "yes")


def _number(env: str, default: float) -> float:
    raw = os.environ.get(env)
    if raw is None:
        return default
    try:
        value = float(raw)
    except ValueError:
        raise RewardSandboxError(f"{env}={raw!r} is not a number") from None
    if not value > 0:
        raise RewardSandboxError(f"{env}={raw!r} must be > 0")
    return value


def call_timeout() -> float:
    return _number(TIMEOUT_ENV, CALL_TIMEOUT_S)


# ---------------------------------------------------------------------------------------------- env members
def _entity(view, name, part, joint):
    return view.handle_link(name, joint) if part == "handle" else view.obj(name)


MEMBERS = {
    "obj_pose": (1, lambda v, n: v.obj_pose(n).raw_pose),
    "obj": (1, lambda v, n: v.obj(n) and None),
    "handle_link": (2, lambda v, n, j: v.handle_link(n, j) and None),
    "entity.pose": (3, lambda v, n, p, j: _entity(v, n, p, j).pose.raw_pose),
    "entity.linear_velocity": (3, lambda v, n, p, j: _entity(v, n, p, j).linear_velocity),
    "entity.angular_velocity": (3, lambda v, n, p, j: _entity(v, n, p, j).angular_velocity),
    "init_obj_pos": (1, lambda v, n: v.init_obj_pos(n)),
    "init_obj_quat": (1, lambda v, n: v.init_obj_quat(n)),
    "obj_height": (1, lambda v, n: v.obj_height(n)),
    "hand_forces": (3, lambda v, n, p, j: v.hand_forces(n, p, j)),
    "palm_pose": (0, lambda v: v.palm_pose.raw_pose),
    "tip_positions": (0, lambda v: v.tip_positions),
    "qpos": (0, lambda v: v.agent.robot.get_qpos()),
    "qvel": (0, lambda v: v.agent.robot.get_qvel()),
    "handle_pos": (2, lambda v, n, j: v.handle_pos(n, j)),
    "joint_qpos": (2, lambda v, n, j: v.joint_qpos(n, j)),
    "joint_open_fraction": (2, lambda v, n, j: v.joint_open_fraction(n, j)),
    "holds_point": (2, lambda v, n, j: v.holds_point(n, j)),
    "wiped_share": (2, lambda v, n, t: v.wiped_share(n, t)),
    "poured_share": (2, lambda v, n, t: v.poured_share(n, t)),
    "goal_pos": (0, lambda v: v.goal_pos),
    "spec_success": (0, lambda v: v.spec_success()),
}
"""What the worker may ask for: member -> (number of arguments, how the real view answers)."""


def _key(raw) -> tuple:
    """A requested key, checked: a known member and its arguments, each a short string or None."""
    if not (isinstance(raw, list) and raw and raw[0] in MEMBERS and len(raw) == MEMBERS[raw[0]][0] + 1):
        raise protocol.ProtocolError(f"unknown env member request {str(raw)[:200]}")
    for a in raw[1:]:
        if not (a is None or isinstance(a, str) and len(a) <= MAX_KEY_ARG_CHARS):
            raise TypeError(f"object and joint names are strings, got {str(a)[:80]!r}")
    if raw[0] in _WITH_PART and (raw[2] not in (None, "handle") or raw[2] is None and raw[3] is not None):
        raise TypeError(f"part is None (the object itself, with no joint) or 'handle', got part {str(raw[2])[:80]!r} "
                        f"and joint {str(raw[3])[:80]!r}")
    return tuple(raw)


_WITH_PART = ("entity.pose", "entity.linear_velocity", "entity.angular_velocity", "hand_forces")
"""Members whose second argument is the part of an object (None or "handle")."""
MAX_PREFETCH_KEYS = 256
"""Keys sent ahead with every call of one function (a reward module reads a few dozen); keys asked for beyond them
are answered on demand within the call's time limit, so a flood of distinct requests cannot grow the parent's
per-call work without bound."""


_LIMIT_ERRORS: dict[type, type] = {}


def _limit_error(base: type) -> type:
    """A :class:`RewardSandboxError` that is also ``base`` and bears its name (``RuntimeError`` for torch's failed
    allocation), so that a report of the form "raised RuntimeError: ..." reads as it does in-process."""
    if base not in _LIMIT_ERRORS:
        _LIMIT_ERRORS[base] = type(base.__name__, (RewardSandboxError, base), {"__module__": __name__})
    return _LIMIT_ERRORS[base]


_CODE_ERRORS: dict[type, type] = {}


def _code_error(base: type) -> type:
    """A :class:`~gendex_envs.errors.GenDexError` that is also ``base`` (a builtin exception reward code raised in
    the worker) and bears its name: callers that catch ``IndexError`` still do, and the error names the module."""
    if base not in _CODE_ERRORS:
        try:
            _CODE_ERRORS[base] = type(base.__name__, (GenDexError, base), {"__module__": __name__})
        except TypeError:  # a base whose instance layout does not mix
            _CODE_ERRORS[base] = RewardModuleError
    return _CODE_ERRORS[base]


def _at_line(exc: BaseException, path: Path, line) -> BaseException:
    """``exc`` with a traceback frame at ``path``:``line`` (where the worker saw it raised), as an in-process
    call's traceback would have."""
    if type(line) is not int or not 0 < line <= 1_000_000:
        return exc
    try:
        exec(compile("\n" * (line - 1) + "raise exc", str(path), "exec"), {"exc": exc})
    except type(exc) as raised:
        return raised
    return exc


def replay_enabled() -> bool:
    return os.environ.get(REPLAY_ENV, "").strip().lower() not in ("0", "false", "no")


def agree(a, b) -> bool:
    """``a`` and ``b`` hold the same values: the same structure, tensors of one dtype and shape, floating ones equal
    to rounding (the worker computes with one thread, the parent with several), all others exactly."""
    if isinstance(a, torch.Tensor) or isinstance(b, torch.Tensor):
        if not (isinstance(a, torch.Tensor) and isinstance(b, torch.Tensor) and a.dtype == b.dtype
                and a.shape == b.shape):
            return False
        b = b.to(a.device)
        if a.is_floating_point():
            return bool(torch.allclose(a, b, rtol=1e-5, atol=1e-6, equal_nan=True))
        return bool(torch.equal(a, b))
    if isinstance(a, dict) and isinstance(b, dict):
        return list(a) == list(b) and all(agree(a[k], b[k]) for k in a)
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(agree(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return type(a) is type(b) and a == b


def _same(a, b) -> bool:
    """``a`` is ``b``, or both are dicts holding the very same objects under the same keys (the env hands
    ``_get_obs_extra`` and ``compute_dense_reward`` each a fresh dict of one step's info tensors)."""
    if a is b:
        return True
    return (isinstance(a, dict) and isinstance(b, dict) and len(a) == len(b)
            and all(k in b and b[k] is v for k, v in a.items()))


def _source_reader(source: list, arity: int):
    """How a replay reads a leaf: ``(view, args) -> tensor`` for an env member the worker may ask for, or an entry of
    one of ``arity`` arguments; raises for any other source."""
    if source[0] == "m":
        key = _key(list(source[1:]))
        member, rest = MEMBERS[key[0]][1], key[1:]
        return lambda view, args: member(view, *rest)
    if not (source[0] == "a" and len(source) >= 2 and type(source[1]) is int and 0 <= source[1] < arity
            and all(type(p) is int and 0 <= p < 4096 or type(p) is str and len(p) <= 256 for p in source[2:])):
        raise ValueError(f"not a member or argument entry: {str(source)[:100]}")
    index, path = source[1], tuple(source[2:])

    def read(view, args):
        value = args[index]
        for part in path:
            value = value[part]
        return value
    return read


# ---------------------------------------------------------------------------------------------- the worker
class _Spawner:
    """One long-lived thread starts every worker: ``PR_SET_PDEATHSIG`` fires when the *thread* that started a
    child ends, so a worker started from a short-lived thread would die with it."""

    def __init__(self):
        self.jobs: queue.Queue = queue.Queue()
        threading.Thread(target=self._run, name="gendex-sandbox-spawner", daemon=True).start()

    def _run(self):
        while True:
            fn, box, done = self.jobs.get()
            try:
                box.append((True, fn()))
            except BaseException as exc:
                box.append((False, exc))
            done.set()

    def run(self, fn):
        box, done = [], threading.Event()
        self.jobs.put((fn, box, done))
        done.wait()
        ok, value = box[0]
        if not ok:
            raise value
        return value


_spawner: _Spawner | None = None
_spawner_lock = threading.Lock()


def _spawn(argv: list[str], env: dict) -> subprocess.Popen:
    global _spawner
    with _spawner_lock:
        if _spawner is None:
            _spawner = _Spawner()
    return _spawner.run(lambda: subprocess.Popen(
        argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
        stderr=None if log.isEnabledFor(logging.DEBUG) else subprocess.DEVNULL,
        close_fds=True, cwd="/", env=env))


def _kill(proc: subprocess.Popen, pidfd: int | None = None) -> None:
    """SIGKILL and reap; through the pidfd when there is one (``pidfd_send_signal`` raises no audit event, so a
    hook that refuses ``os.kill`` while reward code runs, as the probe's does, cannot keep the worker alive)."""
    if proc.poll() is None:
        try:
            if pidfd is not None:
                signal.pidfd_send_signal(pidfd, signal.SIGKILL)
            else:
                proc.kill()
        except OSError:
            pass
    try:
        proc.wait(timeout=10)
    except subprocess.TimeoutExpired:  # pragma: no cover (SIGKILL)
        pass
    for f in (proc.stdin, proc.stdout):
        try:
            f.close()
        except OSError:
            pass
    if pidfd is not None:
        try:
            os.close(pidfd)
        except OSError:
            pass


class Worker:
    """A confined worker process and its two pipes; calls are serialised by a lock."""

    def __init__(self):
        self.memory = int(_number(MEMORY_ENV, confine.MEMORY_LIMIT_BYTES / 2**20) * 2**20)
        self.cpu = int(_number(CPU_ENV, confine.CPU_LIMIT_S))
        env = {"PATH": os.defpath, "LANG": "C.UTF-8", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
               "OPENBLAS_NUM_THREADS": "1"}
        self.proc = _spawn([sys.executable, "-I", str(WORKER), str(os.getpid()), str(self.memory), str(self.cpu)], env)
        self.owner = os.getpid()
        self.rfd, self.wfd = self.proc.stdout.fileno(), self.proc.stdin.fileno()
        os.set_blocking(self.wfd, False)
        self.lock = threading.RLock()
        self.dead: str | None = None
        try:
            pidfd = os.pidfd_open(self.proc.pid)
        except (AttributeError, OSError):  # before Linux 5.3
            pidfd = None
        self._finalizer = weakref.finalize(self, _kill, self.proc, pidfd)
        self.next_id = 0
        try:
            msg = self.read(time.monotonic() + START_TIMEOUT_S)
        except (RewardTimeoutError, RewardSandboxError, protocol.ProtocolError, EOFError) as exc:
            self.stop(f"it did not start: {exc}")
            raise RewardSandboxError(f"the reward sandbox's worker did not start: {exc}") from None
        if msg.get("op") != "ready":
            self.stop("unconfined")
            raise RewardSandboxError(
                f"untrusted reward code runs only in a confined worker process, and this system cannot confine one: "
                f"{str(msg.get('msg'))[:500]}. trust_remote_code=True runs a folder you wrote as it is; "
                f"{IN_PROCESS_ENV}=1 runs untrusted folders in this process under the weaker runtime guard only")
        self.walls = [str(w) for w in msg.get("walls", [])][:20]
        log.info("reward sandbox: worker %d started; walls: %s", self.proc.pid, "; ".join(self.walls))

    def alive(self) -> bool:
        return self.dead is None and self.owner == os.getpid() and self.proc.poll() is None

    def stop(self, why: str) -> None:
        if self.dead is None:
            self.dead = why
        self._finalizer()

    # ---- raw I/O with a deadline
    def _wait(self, fd: int, events: int, deadline: float) -> None:
        poller = select.poll()
        poller.register(fd, events)
        remaining = deadline - time.monotonic()
        if remaining <= 0 or not poller.poll(remaining * 1000):
            raise RewardTimeoutError("deadline")

    def read(self, deadline: float, device=None) -> dict:
        return protocol.read_frame(self.rfd, lambda: self._wait(self.rfd, select.POLLIN, deadline), device)

    def write(self, header: dict, tensors: list, deadline: float) -> None:
        data = memoryview(b"".join(protocol.frame(header, tensors)))
        while data:
            try:
                data = data[os.write(self.wfd, data):]
            except BlockingIOError:
                self._wait(self.wfd, select.POLLOUT, deadline)

    def why_dead(self) -> str:
        try:
            code = self.proc.wait(timeout=2)
        except subprocess.TimeoutExpired:
            code = None
        if code is None:
            return "it stopped answering"
        if code in (-signal.SIGXCPU, -signal.SIGKILL) and self.dead is None:
            return (f"it ended with signal {-code} (its CPU-time limit is {self.cpu} s, {CPU_ENV} raises it; "
                    f"its memory limit {self.memory >> 20} MiB, {MEMORY_ENV})")
        return f"it exited with status {code}"


_shared: Worker | None = None
_shared_lock = threading.Lock()
_live: weakref.WeakSet = weakref.WeakSet()


def shared_worker() -> Worker:
    """This process's worker (started on first use, or again after the last one died). One worker serves every
    untrusted module of the process: starting one costs about 2 s (importing torch), loading a module into a
    running one a millisecond. It lives until :func:`shutdown`, the process's exit (``atexit``) or the parent's
    death (``PR_SET_PDEATHSIG``), whichever comes first; a dead one is replaced on the next call."""
    global _shared
    with _shared_lock:
        worker = _shared
        if worker is None or not worker.alive():
            worker = _shared = Worker()
            _live.add(worker)
        return worker


@atexit.register
def shutdown() -> None:
    """Stop every worker of this process (modules loaded in them start a new one if called again)."""
    global _shared
    _shared = None
    for worker in list(_live):
        worker.stop("shut down")


# ---------------------------------------------------------------------------------------------- loaded modules
class RemoteModule:
    """One untrusted reward module, loaded in the worker; :meth:`call` runs one of its functions."""

    def __init__(self, path: Path, source: str, full_builtins: bool = False):
        self.path, self.source, self.full_builtins = path, source, full_builtins
        self.prefetch: dict[str, dict[tuple, None]] = {}
        self.worker: Worker | None = None
        self.early: tuple | None = None  # (env, info, elapsed_steps, reward) computed with _get_obs_extra
        self.functions: tuple[str, ...] = ()
        self.reward_max = 1.0
        self.graphs: dict[tuple, list[replay.Graph]] = {}
        self.graph_worker: Worker | None = None  # the worker whose recordings self.graphs holds
        self.traces_left: dict[str, int] = {}
        self.replays: dict[str, int] = {}
        """Per function: calls replayed in this process, and (``worker_calls``) calls the worker served."""
        self.worker_calls: dict[str, int] = {}
        self.replay_off: str | None = None if replay_enabled() else f"{REPLAY_ENV}=0"
        self._load()

    def _load(self) -> None:
        worker = shared_worker()
        with worker.lock:
            worker.next_id += 1
            self.id = worker.next_id
            header = {"op": "load", "id": self.id, "name": f"gendex_reward_{self.id}", "filename": str(self.path),
                      "source": self.source, "full_builtins": self.full_builtins}
            try:
                reply = self._exchange(worker, header, [], "import", None, time.monotonic() + call_timeout())
            except RewardSandboxError:
                raise
            except Exception as exc:  # the module's own error, as the in-process path reports it
                raise RewardModuleError(f"reward module {self.path} failed to import: {type(exc).__name__}: "
                                        f"{exc}") from exc
        self.worker = worker
        if reply.get("op") != "loaded" or not isinstance(reply.get("functions"), list):
            raise RewardSandboxError(f"reward module {self.path}: the worker's reply to loading it is malformed")
        self.functions = tuple(f for f in reply["functions"] if isinstance(f, str))
        self.early_reward = reply.get("early_reward") is True
        reward_max = reply.get("reward_max")
        self.reward_max = float(reward_max) if isinstance(reward_max, int | float) else float("nan")

    def call(self, fn: str, env, args: tuple, info=None):
        """``fn(view, *args)`` in the worker. ``info``: the env's own info object passed to ``_get_obs_extra`` or
        ``compute_dense_reward`` (before :func:`~gendex_envs.reward_view.reward_info`).

        ManiSkill's step calls ``evaluate``, then ``_get_obs_extra(info)``, then ``compute_dense_reward(obs, action,
        info)`` with the same ``info`` and no change of state in between. When the module's reward function reads
        neither ``obs`` nor ``action`` (the worker checks its bytecode), the ``_get_obs_extra`` call computes the
        reward right after the extras, in the same round trip and from the same snapshot; the following
        ``compute_dense_reward`` call returns it if it comes next for the same env, the same ``info`` (the same
        tensor objects under the same keys) and the same ``elapsed_steps``, else it runs as usual. Two round
        trips a step instead of three.

        Before any of that, a call whose function and argument signature have a kept recording is replayed in this
        process (:mod:`gendex_envs.sandbox.replay`; up to :data:`MAX_VARIANTS` graphs, tried in turn); a call the
        worker serves is recorded (at most :data:`MAX_TRACES` times per function) and the recording kept when it
        passes :meth:`_keep`. Replays are audited against the worker (:data:`AUDIT_AT`, :data:`AUDIT_EVERY`)."""
        from gendex_envs.reward_view import view_of

        early, self.early = self.early, None
        u = getattr(env, "unwrapped", env)
        steps = getattr(u, "elapsed_steps", None)
        if fn == "compute_dense_reward" and early is not None and early[0] is u and _same(early[1], info) and \
                isinstance(steps, torch.Tensor) and torch.equal(early[2], steps):
            return early[3]
        view = view_of(env)
        signature = None
        if self.graphs and (self.graph_worker is not self.worker or self.worker is None or not self.worker.alive()):
            self.graphs.clear()  # a recording is worth what the worker that made it is: not past its end
        if self.replay_off is None:
            signature = (fn, view.num_envs, view.table_height, tuple(view.object_names),
                         tuple(view.stage_targets), replay.signature(args))
            for graph in self.graphs.get(signature, ()):
                start = time.perf_counter()
                try:
                    value = graph.run(view, args)
                except replay.Miss as miss:
                    log.debug("reward module %s: %s: replay missed (%s)", self.path, fn, miss)
                    continue
                finally:
                    self._timed(fn, time.perf_counter() - start)
                count = self.replays[fn] = self.replays.get(fn, 0) + 1
                if count % AUDIT_EVERY == 0 or count in AUDIT_AT:
                    self._audit(fn, env, args, info, value)
                return value
        record = signature is not None and self.traces_left.get(fn, MAX_TRACES) > 0
        self.worker_calls[fn] = self.worker_calls.get(fn, 0) + 1
        value, graph = self._remote(fn, env, view, args, info, steps, record)
        if record:
            self.traces_left[fn] = self.traces_left.get(fn, MAX_TRACES) - 1
            self._keep(fn, signature, graph, view, args, value)
        return value

    def _remote(self, fn: str, env, view, args: tuple, info, steps, record: bool, early: bool = True):
        """``fn`` called in the worker: its value, and with ``record`` the graph the worker recorded (or None).
        ``early``: a ``_get_obs_extra`` call may compute the reward too (not for recordings and audits, whose
        values only check the replay's)."""
        if self.worker is None or not self.worker.alive():
            self._load()  # the worker died (a limit, another module's timeout): modules keep no state, reload
        worker = self.worker
        device = torch.device(view.device)
        then = (fn == "_get_obs_extra" and self.early_reward and info is not None and isinstance(steps, torch.Tensor)
                and not record and early)
        keys = dict(self.prefetch.setdefault(fn, {}))
        if then:
            keys.update(self.prefetch.setdefault("compute_dense_reward", {}))
        tensors: list = []
        snapshot = []
        for key in keys:
            try:
                value = MEMBERS[key[0]][1](view, *key[1:])
            except Exception:
                continue
            snapshot.append([list(key), protocol.encode(value, tensors)])
        static = {"num_envs": view.num_envs, "table_height": view.table_height,
                  "object_names": list(view.object_names), "stage_targets": list(view.stage_targets)}
        header = {"op": "call", "id": self.id, "fn": fn, "then": then, "trace": record, "snapshot": snapshot,
                  "static": protocol.encode(static, tensors), "args": protocol.encode(list(args), tensors)}
        with worker.lock:
            reply = self._exchange(worker, header, tensors, fn, view, time.monotonic() + call_timeout(), device)
        after = reply.get("then")
        if then and isinstance(after, list) and len(after) == 1:
            self.early = (getattr(env, "unwrapped", env), info, steps.clone(), after[0])
        return reply.get("value"), reply.get("graph") if record else None

    def _keep(self, fn: str, signature: tuple, graph, view, args: tuple, value) -> None:
        """Check the worker's recording of a call and keep it when its replay, on the very state the call read,
        gives the value the worker returned (:mod:`gendex_envs.sandbox.replay`)."""
        if not (isinstance(graph, dict) and "entries" in graph):
            why = graph.get("failed") if isinstance(graph, dict) else "no graph"
            log.debug("reward module %s: %s is served by the worker: %s", self.path, fn, str(why)[:300])
            return
        arity = ARITY[fn]
        try:
            compiled = replay.compile_graph(graph, view.num_envs, torch.device(view.device),
                                            lambda source: _source_reader(source, arity))
            start = time.perf_counter()
            try:
                replayed = compiled.run(view, args)
            finally:
                self._timed(fn, time.perf_counter() - start)
        except (replay.GraphError, replay.Miss) as exc:
            log.debug("reward module %s: %s's recording is not replayed: %s", self.path, fn, exc)
            return
        if self.replay_off is not None:
            return
        if not agree(replayed, value):
            log.debug("reward module %s: %s's replay differs from its call; the worker serves it", self.path, fn)
            return
        if self.graph_worker is not self.worker:
            self.graphs.clear()
            self.graph_worker = self.worker
        kept = self.graphs.setdefault(signature, [])
        kept.insert(0, compiled)
        del kept[MAX_VARIANTS:]
        log.debug("reward module %s: %s replays in process (%d leaves, %d operations)", self.path, fn,
                  compiled.leaves, compiled.ops)

    def _timed(self, fn: str, seconds: float) -> None:
        if seconds > REPLAY_SLOW_S and self.replay_off is None:
            self.replay_off = f"a replay of {fn} took {seconds:.2f} s (more than {REPLAY_SLOW_S} s)"
            self.graphs.clear()
            log.warning("reward module %s: %s; its calls go to the worker from now on", self.path, self.replay_off)

    def _audit(self, fn: str, env, args: tuple, info, value) -> None:
        """Ask the worker for a replayed call too; when the two differ, stop replaying this module."""
        from gendex_envs.reward_view import view_of

        u = getattr(env, "unwrapped", env)
        worker_value, _ = self._remote(fn, env, view_of(env), args, info, getattr(u, "elapsed_steps", None), False,
                                       early=False)
        if not agree(value, worker_value):
            self.replay_off = f"{fn}'s replay differed from the worker's call"
            self.graphs.clear()
            log.warning("reward module %s: %s; its calls go to the worker from now on", self.path, self.replay_off)

    def _exchange(self, worker: Worker, header: dict, tensors: list, fn: str, answer, deadline: float,
                  device=None) -> dict:
        """Send a request and serve the worker's ``get`` requests until its reply; every failure is typed."""
        errors: dict[str, BaseException] = {}
        where = f"reward module {self.path}: {fn}"
        try:
            worker.write(header, tensors, deadline)
            while True:
                msg = worker.read(deadline, device)
                op = msg.get("op")
                if op == "get" and answer is not None:
                    view, out = answer, []
                    keys = self.prefetch.setdefault(msg.get("fn") if msg.get("fn") in FUNCTIONS else fn, {})
                    try:
                        key = _key(msg.get("key"))
                    except TypeError as exc:  # our own refusal of the request, not the real view's
                        exc = RewardModuleError(f"{where}: {exc}")
                        worker.write({"op": "err", "type": "TypeError", "msg": str(exc)[:4000]}, [], deadline)
                        errors["TypeError"] = exc
                        continue
                    try:
                        value = MEMBERS[key[0]][1](view, *key[1:])
                    except Exception as exc:  # the real view's error, raised in the worker as is
                        errors[type(exc).__name__] = exc
                        worker.write({"op": "err", "type": type(exc).__name__, "msg": str(exc)[:4000]}, [], deadline)
                        continue
                    if len(keys) < MAX_PREFETCH_KEYS:
                        keys[key] = None
                    worker.write({"op": "val", "value": protocol.encode(value, out)}, out, deadline)
                elif op in ("ret", "loaded"):
                    return msg
                elif op == "exc":
                    failure = self._error(msg, where, errors)
                    break
                else:
                    raise protocol.ProtocolError(f"unexpected reply {str(op)[:50]}")
        except RewardTimeoutError:
            worker.stop(f"{where} ran past the limit")
            limit = call_timeout()
            raise RewardTimeoutError(
                f"{where} ran longer than {limit:g} s (the sandbox's wall-clock limit per call, CALL_TIMEOUT_S); "
                f"the worker was stopped. Set {TIMEOUT_ENV} to allow more") from None
        except (protocol.ProtocolError, EOFError, OSError, ValueError, TypeError) as exc:
            why = worker.why_dead() if isinstance(exc, EOFError | BrokenPipeError) else f"malformed reply: {exc}"
            worker.stop(why)
            raise RewardSandboxError(f"{where}: the sandbox's worker failed ({why}); it was stopped") from None
        raise failure

    def _error(self, msg: dict, where: str, errors: dict) -> BaseException:
        name, text = str(msg.get("type"))[:100], str(msg.get("msg"))[:4000]
        if msg.get("remote") is True and name in errors:
            return errors[name]  # the real view's own error (an unknown object, a task without goal)
        if msg.get("memory") is True:
            base = getattr(builtins, name, None)
            base = base if base in (MemoryError, RuntimeError) else RuntimeError
            return _at_line(_limit_error(base)(
                f"{text} ({where} ran out of memory in the sandbox: the worker's limit is "
                f"{self.worker_memory() >> 20} MiB; {MEMORY_ENV} raises it)"), self.path, msg.get("line"))
        if name == "UntrustedCodeError":
            from gendex_envs.guard import UntrustedCodeError

            return UntrustedCodeError(f"{where}: {text}")
        cls = getattr(builtins, name, None)
        if isinstance(cls, type) and issubclass(cls, Exception) and not issubclass(cls, OSError):
            try:  # a GenDex error that is also what the module raised, at the module's line (as in-process)
                return _at_line(_code_error(cls)(f"{where} raised {name}: {text}"), self.path, msg.get("line"))
            except Exception:
                pass
        return RewardModuleError(f"{where} raised {name}: {text}")

    def worker_memory(self) -> int:
        return self.worker.memory if self.worker is not None else confine.MEMORY_LIMIT_BYTES

