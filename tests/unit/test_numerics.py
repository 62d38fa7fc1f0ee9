"""gendex.data.numerics: a dataset build's workers run every CPU-dispatched library on its baseline x86-64 path,
and a worker whose switches did not take refuses to collect."""

from __future__ import annotations

import os

import pytest

from gendex.data import numerics
from gendex.fanout import Backend, ordered_map

pytestmark = pytest.mark.skipif(not numerics.supported(), reason="the pinned numerics are x86-64's")


def _make_prober():
    def probe(_job):
        import numpy as np
        import torch

        a = np.linspace(0.1, 3.0, 1001)
        return (numerics.problems(), torch.backends.cpu.get_cpu_capability(),
                float(np.sin(a).sum()), os.environ.get("GLIBC_TUNABLES"))
    return probe


def _make_checker():
    numerics.check()
    return lambda job: job


def test_a_pinned_worker_runs_the_baseline_kernels_and_this_process_does_not():
    backend = numerics.pinned_backend(None)
    assert backend.kind == "process" and backend.workers == 1 and dict(backend.env) == dict(numerics.PINNED_ENV)
    [(found, capability, _, tunables)] = list(ordered_map(_make_prober, [0], backend))
    assert found == [] and capability == "DEFAULT" and tunables == numerics.PINNED_ENV["GLIBC_TUNABLES"]
    # this test process loaded numpy and torch with the CPU's own kernels: numpy dispatches above SSE3 on any x86-64
    # made since 2008, and the problems say which library and why
    assert any("numpy dispatches to" in p for p in numerics.problems())
    assert numerics.pinned_backend(Backend("process", 2)).workers == 2
    assert numerics.pinned_backend(Backend("ray", 3)).kind == "ray"


def test_a_worker_meant_to_be_pinned_whose_switches_did_not_take_refuses():
    """Only the marker, none of the switches: the worker's numpy and torch load with the CPU's own kernels."""
    backend = Backend("process", 1, env=((numerics.MARKER, numerics.NUMERICS),))
    with pytest.raises(numerics.NumericsError, match="pinned numerics, but .*numpy dispatches"):
        list(ordered_map(_make_checker, [0], backend))
    numerics.check()  # this process was not started to be pinned: nothing to check


def test_the_pinned_numerics_are_refused_off_x86(monkeypatch):
    monkeypatch.setattr(numerics.platform, "machine", lambda: "aarch64")
    with pytest.raises(numerics.NumericsError, match="aarch64 .*allowed: x86_64"):
        numerics.pinned_backend(None)


def test_an_instruction_set_numpy_has_no_kernels_for_is_no_problem(monkeypatch):
    """numpy 1.26 on a Sapphire Rapids reports AVX512_SPR as on even under NPY_DISABLE_CPU_FEATURES (it ignores a
    name it does not dispatch to); only the sets it has kernels for count."""
    compiled = frozenset(numerics._NUMPY_DISPATCH.split()) - {"AVX512_SPR"}
    monkeypatch.setattr(numerics, "_numpy_cpu_features", lambda: ({"SSE3": True, "AVX512_SPR": True}, compiled))
    assert not any("numpy dispatches" in p for p in numerics.problems())
    monkeypatch.setattr(numerics, "_numpy_cpu_features", lambda: ({"AVX2": True, "AVX512_SPR": True}, compiled))
    assert any("numpy dispatches to AVX2 (" in p for p in numerics.problems())
