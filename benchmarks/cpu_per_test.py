"""A pytest plugin for ``benchmarks/suite_scale.py``: the CPU seconds each test costs, written per worker process.

Per test: the CPU time of the worker process (all its threads) plus that of the child processes it waited for while
the test ran (``RUSAGE_CHILDREN``), from the start of its setup to the end of its teardown. Unlike a test's wall time
this hardly depends on what else the machine runs, so two suites can be compared test by test.

Load with ``-p cpu_per_test`` (``benchmarks/`` on ``PYTHONPATH``) and ``GENDEX_CPU_JSON=PREFIX``: each process writes
``PREFIX.<worker>.json`` (``{nodeid: seconds}``) at the end of its session.
"""

from __future__ import annotations

import json
import os
import resource
import time
from pathlib import Path

import pytest

_SECONDS: dict[str, float] = {}


def _cpu() -> float:
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + kids.ru_utime + kids.ru_stime


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    start = _cpu()
    yield
    _SECONDS[item.nodeid] = _SECONDS.get(item.nodeid, 0.0) + _cpu() - start


def pytest_sessionfinish(session):
    prefix = os.environ.get("GENDEX_CPU_JSON")
    if prefix and _SECONDS:
        worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
        Path(f"{prefix}.{worker}.json").write_text(json.dumps(_SECONDS, indent=0, sort_keys=True))
