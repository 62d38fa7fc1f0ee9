"""gendex.fanout: jobs come back in order on every backend, a worker is built once per process, and a worker process
killed mid-job is replaced with nothing lost or duplicated (Ray)."""

from __future__ import annotations

import functools
import os
import sys
import time
from pathlib import Path

import pytest

from gendex.fanout import Backend, FanOutError, ordered_map


class Squarer:
    """A worker with state: counts the jobs its process ran; the first job it runs in a process sleeps longest so
    that jobs finish out of order."""

    def __init__(self, die_once_at: int | None = None, marker: str | None = None):
        self.pid = os.getpid()
        self.calls = 0
        self.die_once_at, self.marker = die_once_at, marker

    def __call__(self, job: int) -> tuple[int, int, int]:
        self.calls += 1
        if job == self.die_once_at and self.marker and not Path(self.marker).exists():
            Path(self.marker).write_text(str(os.getpid()))
            os._exit(9)  # the process dies mid-job, as a killed worker would
        time.sleep(0.05 * ((7 * job) % 5))
        return job, job * job, self.pid


def _make(die_once_at=None, marker=None):
    return Squarer(die_once_at, marker)


def _make_env_reader():
    return lambda name: (name, os.environ.get(name), os.getpid())


@pytest.fixture(scope="module")
def ray_cluster():
    ray = pytest.importorskip("ray", reason="the ray extra is installed by scripts/setup.sh")
    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])  # workers cannot import this test module
    from gendex.fanout import ray_init

    ray_init(None, 2)
    yield ray
    ray.shutdown()


def test_backends_are_validated_with_named_reasons():
    with pytest.raises(FanOutError, match="not one of"):
        Backend("dask")
    with pytest.raises(FanOutError, match="integer >= 1"):
        Backend("process", 0)
    with pytest.raises(FanOutError, match="needs the ray backend"):
        Backend("process", 2, "ray://head:10001")
    assert Backend.from_options(1) == Backend()
    assert Backend.from_options(2) == Backend("process", 2)
    assert Backend.from_options(2, ray=True) == Backend("ray", 2)
    assert Backend.from_options(1, ray_address="auto") == Backend("ray", 1, "auto")
    with pytest.raises(FanOutError, match="needs the process or ray backend"):
        Backend("local", env=(("GENDEX_FANOUT_TEST", "1"),))


def test_local_and_process_backends_return_jobs_in_order():
    jobs = list(range(12))
    local = list(ordered_map(_make, jobs))
    assert [r[:2] for r in local] == [(j, j * j) for j in jobs] and {r[2] for r in local} == {os.getpid()}
    procs = list(ordered_map(_make, jobs, Backend("process", 2)))
    assert [r[:2] for r in procs] == [r[:2] for r in local]
    assert len({r[2] for r in procs}) == 2 and os.getpid() not in {r[2] for r in procs}


def test_stopping_early_submits_only_a_bounded_number_of_jobs(ray_cluster):
    taken = []

    def jobs():
        for j in range(1000):
            taken.append(j)
            yield j

    got = []
    for r in ordered_map(_make, jobs(), Backend("ray", 2)):
        got.append(r[0])
        if len(got) == 5:
            break
    assert got == [0, 1, 2, 3, 4] and len(taken) <= 5 + 8 * 2  # at most 8 * workers ahead


def test_ray_backend_survives_a_worker_killed_mid_job(ray_cluster, tmp_path):
    marker = tmp_path / "died"
    jobs = list(range(16))
    got = list(ordered_map(functools.partial(_make, 6, str(marker)), jobs, Backend("ray", 2)))
    assert marker.exists()  # a worker process did die on job 6
    assert [r[:2] for r in got] == [(j, j * j) for j in jobs]  # nothing lost, nothing duplicated, in order
    dead = int(marker.read_text())
    assert got[6][2] != dead  # job 6 was re-run by another process
    assert len({r[2] for r in got}) >= 2


def test_worker_processes_start_with_the_backends_environment(ray_cluster):
    """A library that reads a switch when it loads (numpy, torch) sees it only if the worker process starts with
    it: the process and ray backends start theirs with ``env``, and this process's environment is left as it was."""
    env = (("GENDEX_FANOUT_TEST", "pinned"),)
    assert "GENDEX_FANOUT_TEST" not in os.environ
    for backend in (Backend("process", 2, env=env), Backend("ray", 2, env=env)):
        got = list(ordered_map(_make_env_reader, ["GENDEX_FANOUT_TEST"] * 4, backend))
        assert {r[1] for r in got} == {"pinned"} and os.getpid() not in {r[2] for r in got}, backend
    assert "GENDEX_FANOUT_TEST" not in os.environ
    plain = list(ordered_map(_make_env_reader, ["GENDEX_FANOUT_TEST"] * 2, Backend("process", 2)))
    assert {r[1] for r in plain} == {None}


class _StuckPool:
    """A pool whose terminate() never returns, as Pool.terminate did when its task feeder hung."""

    def __init__(self):
        import threading

        self.called = threading.Event()

    def terminate(self):
        import threading

        self.called.set()
        threading.Event().wait()


def test_a_pool_whose_terminate_hangs_has_its_workers_killed(monkeypatch):
    import multiprocessing

    from gendex import fanout

    before = set(multiprocessing.active_children())
    worker = multiprocessing.get_context("spawn").Process(target=time.sleep, args=(120,), daemon=True)
    worker.start()
    monkeypatch.setattr(fanout, "TERMINATE_WAIT_S", 0.5)
    pool = _StuckPool()
    t0 = time.monotonic()
    fanout._terminate(pool, before)
    assert pool.called.is_set() and time.monotonic() - t0 < 10
    worker.join(10)
    assert not worker.is_alive() and worker.exitcode is not None and worker.exitcode < 0  # killed, not finished
