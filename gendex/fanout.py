"""Fan-out of independent jobs, in order: in this process, in local worker processes, or on a Ray cluster.

Collection attempts, dataset builds, evaluation tasks and ablation cells are all "run this job on a worker that
keeps its env alive, give me the results in job order". :func:`ordered_map` does exactly that for one
:class:`Backend`:

``local``
    one worker in this process (the default; what every result is compared against).
``process``
    ``workers`` local processes (``multiprocessing``, spawn), one worker object each.
``ray``
    ``workers`` Ray actors, on a local instance this call starts (``--ray``) or on a running cluster
    (``--ray-address ADDR``). Actors are created with ``max_restarts=-1, max_task_retries=-1``: when a worker
    process dies mid-job (killed, out of memory, a lost node), Ray starts a new one, which builds its worker again,
    and re-runs the jobs that process had not finished. Results are consumed strictly in job order and each job
    result is taken once, so nothing is lost or duplicated; with history-independent jobs (an attempt depends only
    on its seed) the output is identical to the local backend's.

Jobs are submitted ahead of consumption, at most ``8 * workers`` past the last one consumed, so a slow job at the
head of the line does not leave the other workers idle, and a caller that stops early (enough successes) wastes
at most that many jobs. A worker is made once per process by ``make_worker()`` (a picklable
callable: a module-level function or a :func:`functools.partial` of one) and called as ``worker(job)``.
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import Any, Literal

log = logging.getLogger(__name__)

BackendKind = Literal["local", "process", "ray"]
PER_ACTOR = 2
"""Unfinished jobs per Ray actor: one running and one queued behind it."""
_POLL_S = 0.05
AHEAD_PER_WORKER = 8
"""Jobs submitted past the last one consumed, per worker: a slow job at the head of the line does not idle the
others (the price: up to this many jobs computed for nothing when the caller stops early)."""
KINDS: tuple[str, ...] = ("local", "process", "ray")


class FanOutError(RuntimeError):
    """A fan-out backend was asked for something it cannot do (unknown kind, Ray missing, a bad worker count)."""


@dataclass(frozen=True)
class Backend:
    """Where jobs run: ``kind``, with ``workers`` workers; ``address``: a Ray cluster to join (None: start one);
    ``env``: environment variables the worker processes start with (libraries that read a switch when they load,
    e.g. :data:`gendex.data.numerics.PINNED_ENV`)."""

    kind: BackendKind = "local"
    workers: int = 1
    address: str | None = None
    env: tuple[tuple[str, str], ...] = ()

    def __post_init__(self):
        if self.kind not in KINDS:
            raise FanOutError(f"backend {self.kind!r} is not one of {list(KINDS)}")
        if not isinstance(self.workers, int) or self.workers < 1:
            raise FanOutError(f"workers={self.workers!r}; allowed: an integer >= 1")
        if self.address is not None and self.kind != "ray":
            raise FanOutError(f"a Ray address ({self.address!r}) needs the ray backend, not {self.kind!r}")
        if self.kind == "local" and self.workers != 1:
            raise FanOutError(f"the local backend runs one worker in this process, not {self.workers}")
        if self.kind == "local" and self.env:
            raise FanOutError("the local backend runs in this process, whose environment is already set; worker "
                              f"environment {dict(self.env)} needs the process or ray backend")

    @classmethod
    def from_options(cls, workers: int = 1, ray: bool = False, ray_address: str | None = None) -> Backend:
        """The CLI's ``--workers K [--ray] [--ray-address ADDR]``: Ray when either Ray option is given, else local
        processes when K > 1, else this process."""
        if ray or ray_address:
            return cls("ray", workers, ray_address)
        return cls("process", workers) if workers > 1 else cls()

    def describe(self) -> str:
        if self.kind == "local":
            return "this process"
        where = f"Ray at {self.address}" if self.address else ("a local Ray instance" if self.kind == "ray"
                                                              else "local processes")
        return f"{self.workers} worker{'s' if self.workers > 1 else ''} on {where}"


# ---------------------------------------------------------------------------------------------- process backend
_WORKER: Callable | None = None


class _Unbuilt:
    """Stands for a worker whose ``make_worker()`` raised: each job raises that error, so it reaches the caller
    (a pool's initializer that raises would instead be restarted for ever)."""

    def __init__(self, error: BaseException):
        self.error = error

    def __call__(self, job):
        raise self.error


def _build_worker(make_worker: Callable[[], Callable]) -> Callable:
    _one_thread()
    try:
        return make_worker()
    except Exception as exc:  # any error: it is raised again, in the caller, by the first job
        return _Unbuilt(exc)


def _process_init(make_worker: Callable[[], Callable]) -> None:
    global _WORKER
    _WORKER = _build_worker(make_worker)


TERMINATE_WAIT_S = 30.0
"""How long :func:`_terminate` waits for ``Pool.terminate`` before it kills the pool's workers itself."""


def _terminate(pool, before: set) -> None:
    """``pool.terminate()``, but never a hang: ``Pool.terminate`` joins the pool's task-feeding thread, which can stay
    blocked putting queued jobs to workers that are gone (a gendex-lib-v2 build hung so for 13 minutes after a task's
    last episode; py-spy: the main thread in ``_terminate_pool``'s join, the feeder in ``SimpleQueue.put``). It runs
    in a daemon thread; after :data:`TERMINATE_WAIT_S` the worker processes this pool started (the children that
    were not there before it) are killed and the thread is left to the interpreter's exit."""
    import multiprocessing
    import threading

    done = threading.Thread(target=pool.terminate, name="pool-terminate", daemon=True)
    done.start()
    done.join(TERMINATE_WAIT_S)
    if done.is_alive():
        stray = [p for p in multiprocessing.active_children() if p not in before]
        log.warning("the worker pool did not end within %.0f s; killing its %d worker processes", TERMINATE_WAIT_S,
                    len(stray))
        for p in stray:
            p.kill()


def _process_call(job):
    return _WORKER(job)


def _one_thread() -> None:
    """One worker per core: torch's and OpenBLAS's own thread pools would oversubscribe it. OpenBLAS matters most:
    with two busy processes on two cores, its spinning threads make a 4x4 ``numpy.linalg.inv`` (the solver's hand
    model calls it per link) about 400 times slower (11 s instead of 0.03 s for 2000 batched inverses)."""
    import torch
    from threadpoolctl import threadpool_limits

    torch.set_num_threads(1)
    threadpool_limits(1)


@contextlib.contextmanager
def _environ(env: tuple[tuple[str, str], ...]) -> Iterator[None]:
    """``env`` set in ``os.environ`` for the block (processes started in it inherit it), then restored."""
    saved = {k: os.environ.get(k) for k, _ in env}
    os.environ.update(dict(env))
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


# ---------------------------------------------------------------------------------------------- ray backend
def _ray():
    try:
        import ray
    except ImportError as exc:
        raise FanOutError("the ray backend needs Ray: pip install 'gendex[ray]' (ray>=2.60)") from exc
    return ray


def ray_init(address: str | None, workers: int) -> bool:
    """Start (``address`` None) or join a Ray instance unless one is up; True when this call started it."""
    ray = _ray()
    if ray.is_initialized():
        return False
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")  # no usage reports: nothing here reaches the network
    kwargs: dict[str, Any] = dict(include_dashboard=False, log_to_driver=False, configure_logging=False)
    if address is None:
        kwargs["num_cpus"] = max(workers, os.cpu_count() or 1)
    log.info("starting Ray (%s)", address or "local instance")
    ray.init(address=address, **kwargs)
    return True


def _actor_class():
    ray = _ray()

    @ray.remote(num_cpus=1, max_restarts=-1, max_task_retries=-1)
    class FanOutWorker:
        """One worker object in its own process; Ray rebuilds it (and re-runs its unfinished jobs) if it dies."""

        def __init__(self, make_worker):
            self.worker = _build_worker(make_worker)

        def run(self, job):
            return self.worker(job)

        def pid(self) -> int:
            return os.getpid()

    return FanOutWorker


def _ray_map(make_worker: Callable, jobs: Iterable, backend: Backend, ahead: int) -> Iterator:
    """Jobs go to the least loaded actor (at most :data:`PER_ACTOR` unfinished each, so none idles while the head
    of the line is slow); results are yielded strictly in job order, at most ``ahead`` jobs past the last one."""
    ray = _ray()
    started = ray_init(backend.address, backend.workers)
    options = {"runtime_env": {"env_vars": dict(backend.env)}} if backend.env else {}
    actors = [_actor_class().options(**options).remote(make_worker) for _ in range(backend.workers)]
    in_flight: deque = deque()
    running: dict = {}  # ref -> actor index, for jobs not yet seen finished
    load = [0] * len(actors)
    it = iter(jobs)
    exhausted = False
    try:
        while True:
            if running:
                done, _ = ray.wait(list(running), num_returns=len(running), timeout=0)
                for ref in done:
                    load[running.pop(ref)] -= 1
            while not exhausted and len(in_flight) < ahead and min(load) < PER_ACTOR:
                try:
                    job = next(it)
                except StopIteration:
                    exhausted = True
                    break
                a = load.index(min(load))
                ref = actors[a].run.remote(job)
                in_flight.append(ref)
                running[ref] = a
                load[a] += 1
            if not in_flight:
                return
            head = in_flight[0]
            ready, _ = ray.wait([head], timeout=_POLL_S)
            if ready:
                in_flight.popleft()
                if head in running:
                    load[running.pop(head)] -= 1
                yield ray.get(head)
    finally:
        if started:
            ray.shutdown()  # ends the actors and their unfinished jobs with the instance
        else:
            for actor in actors:  # on a shared cluster: end ours only
                ray.kill(actor)


@contextlib.contextmanager
def session(backend: Backend | None):
    """Keep the backend's cluster up across several :func:`ordered_map` calls (a dataset's tasks, a suite's
    tasks): Ray is started (or joined) once and shut down at the end if this session started it."""
    started = backend is not None and backend.kind == "ray" and ray_init(backend.address, backend.workers)
    try:
        yield backend
    finally:
        if started:
            _ray().shutdown()


# ---------------------------------------------------------------------------------------------- entry point
def ordered_map(make_worker: Callable[[], Callable], jobs: Iterable, backend: Backend | None = None, *,
                ahead: int | None = None) -> Iterator:
    """``worker(job)`` for each job, in job order, on ``backend`` (default: this process); see the module doc.

    A generator: stop consuming to stop submitting (at most ``ahead``, default ``8 * workers``, jobs run past
    the last one consumed). Closing it ends the backend's workers."""
    backend = backend or Backend()
    ahead = ahead or AHEAD_PER_WORKER * backend.workers
    if backend.kind == "local":
        worker = make_worker()
        for job in jobs:
            yield worker(job)
    elif backend.kind == "process":
        import multiprocessing

        before = set(multiprocessing.active_children())
        with _environ(backend.env):  # spawned workers copy this process's environment when they start
            pool = multiprocessing.get_context("spawn").Pool(backend.workers, _process_init, (make_worker,))
        try:  # in order, at most ``ahead`` submitted past the last result taken (jobs are pulled lazily)
            pending: deque = deque()
            it = iter(jobs)
            exhausted = False
            while True:
                while not exhausted and len(pending) < ahead:
                    try:
                        pending.append(pool.apply_async(_process_call, (next(it),)))
                    except StopIteration:
                        exhausted = True
                if not pending:
                    return
                yield pending.popleft().get()
        finally:
            _terminate(pool, before)
    else:
        yield from _ray_map(make_worker, jobs, backend, ahead)


__all__ = ["KINDS", "Backend", "FanOutError", "ordered_map", "ray_init", "session"]
