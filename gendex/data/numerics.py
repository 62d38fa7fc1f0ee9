"""Numerics that do not depend on the CPU, for the collections whose bytes are published (dataset builds).

numpy, torch, OpenBLAS, MKL, oneDNN and glibc's libm each pick their kernels at run time from the CPU's instruction
sets. The same seed then gives the same episode on one kind of CPU, but another kind may round otherwise: a different
vector width sums in another order, a fused multiply-add rounds once instead of twice. On an AMD EPYC with AVX2 two
of three published datasets collected their first attempt differently from the AVX-512 machine that built them; on
that AMD machine, forcing torch's plain kernels (``ATEN_CPU_CAPABILITY=default``) instead of its AVX2 ones changed
``gendex-pickupbottle-v1``'s first attempt, and hiding AVX/FMA from glibc (its libm then takes its plain
``sin``/``exp``/``pow``) changed ``gendex-opencabinet-v1``'s (benchmarks/results/numerics.md).

:data:`PINNED_ENV` sets each library's own switch to its baseline x86-64 path and one thread. The switches are read
when a library loads, so they cannot be turned on in a process that has already imported numpy or torch: a dataset
build runs its attempts in worker processes started with them (:func:`pinned_backend`, also for one worker), and
each worker checks that they took (:func:`check`) before it collects. The build's own process only writes what the
workers return (element-wise sums and extrema, the same on any CPU).

Outside x86-64 these switches mean nothing (an ARM CPU has its own kernels): :func:`supported` says so, and a build
there is refused rather than recorded under checksums that no x86-64 machine reproduces.
"""

from __future__ import annotations

import os
import platform
from collections.abc import Mapping
from dataclasses import replace

from gendex_envs.errors import GenDexError

NUMERICS = "x86-64-baseline-1"
"""The name of the numerics :data:`PINNED_ENV` gives; recorded in a manifest's ``built_with`` (bumped when the
switches change, since builds then give other bytes)."""

MARKER = "GENDEX_PINNED_NUMERICS"
"""Set in a process started with :data:`PINNED_ENV`: :func:`check` then verifies the switches took."""

_NUMPY_DISPATCH = ("SSSE3 SSE41 POPCNT SSE42 AVX F16C FMA3 AVX2 AVX512F AVX512CD AVX512_KNL AVX512_KNM AVX512_SKX "
                   "AVX512_CLX AVX512_CNL AVX512_ICL AVX512_SPR")
"""numpy's run-time dispatched instruction sets above its x86-64 baseline (SSE3); names a CPU lacks are ignored."""

PINNED_ENV: Mapping[str, str] = {
    "ATEN_CPU_CAPABILITY": "default",      # torch: its portable kernels, not the AVX2/AVX-512 ones
    "NPY_DISABLE_CPU_FEATURES": _NUMPY_DISPATCH,  # numpy: the baseline loops (sin, exp, sorting, casts ...)
    "OPENBLAS_CORETYPE": "Prescott",       # numpy's and scipy's OpenBLAS: the SSE3 kernels every x86-64 runs
    "MKL_CBWR": "COMPATIBLE",              # torch's MKL: the conditional-reproducibility path
    "ONEDNN_MAX_CPU_ISA": "SSE41",         # torch's oneDNN (and its older name below)
    "DNNL_MAX_CPU_ISA": "SSE41",
    "GLIBC_TUNABLES": "glibc.cpu.hwcaps=-AVX,-AVX2,-FMA,-FMA4",  # libm's plain sin/exp/pow, not its FMA variants
    "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",  # one thread: one summation order
    MARKER: NUMERICS,
}
"""The environment a dataset build's workers start with."""


class NumericsError(GenDexError):
    """A process that should collect with pinned numerics does not (a switch did not take), or cannot."""


def supported() -> bool:
    """True on x86-64, the only CPU family :data:`PINNED_ENV` pins."""
    return platform.machine().lower() in ("x86_64", "amd64")


def problems() -> list[str]:
    """What in this process does not run as :data:`PINNED_ENV` asks (empty: it does)."""
    import torch
    from threadpoolctl import threadpool_info

    found = []
    if not supported():
        found.append(f"this CPU is {platform.machine()}, not x86-64")
    capability = torch.backends.cpu.get_cpu_capability()
    if capability != "DEFAULT":
        found.append(f"torch runs its {capability} kernels (ATEN_CPU_CAPABILITY was read before it was set)")
    features, compiled = _numpy_cpu_features()
    on = [f for f in _NUMPY_DISPATCH.split() if features.get(f) and f in compiled]
    if on:
        found.append(f"numpy dispatches to {', '.join(on)} (numpy was imported before NPY_DISABLE_CPU_FEATURES)")
    for pool in threadpool_info():
        if pool.get("internal_api") == "openblas" and str(pool.get("architecture", "")).lower() != "prescott":
            found.append(f"OpenBLAS ({pool.get('filepath')}) runs its {pool.get('architecture')} kernels")
    return found


def _numpy_cpu_features() -> tuple[dict[str, bool], frozenset[str]]:
    """numpy's table of the instruction sets it may use (the CPU's, less those disabled), and the sets this numpy
    build has dispatched kernels for (no public name for either: numpy 1 and 2 keep them in their private core
    module, as ``numpy.show_runtime`` reads them).

    A set the CPU has but the build has no kernels for (numpy 1.26 on a Sapphire Rapids: ``AVX512_SPR``) stays on
    in the first table, since ``NPY_DISABLE_CPU_FEATURES`` ignores names the build does not dispatch to; numpy
    never runs code for it, so it is no problem."""
    import importlib

    for name in ("numpy._core._multiarray_umath", "numpy.core._multiarray_umath"):
        try:
            module = importlib.import_module(name)
            features = dict(module.__cpu_features__)
        except (ImportError, AttributeError):
            continue
        return features, frozenset(getattr(module, "__cpu_dispatch__", features))
    return {}, frozenset()


def check() -> None:
    """In a process started with :data:`PINNED_ENV` (its :data:`MARKER` set), raise :class:`NumericsError` when a
    switch did not take; elsewhere do nothing."""
    if os.environ.get(MARKER) != NUMERICS:
        return
    found = problems()
    if found:
        raise NumericsError("this worker was started to collect with pinned numerics, but " + "; ".join(found))


def pinned_backend(backend):
    """``backend`` (:class:`gendex.fanout.Backend`) with its workers started under :data:`PINNED_ENV`; this process
    cannot be pinned after the fact, so one local worker becomes one worker process."""
    if not supported():
        raise NumericsError(f"a dataset build pins x86-64 numerics so that its bytes do not depend on the CPU; this "
                            f"machine is {platform.machine()} (allowed: x86_64)")
    from gendex.fanout import Backend

    backend = backend or Backend()
    kind = "process" if backend.kind == "local" else backend.kind
    return replace(backend, kind=kind, env=tuple(sorted(PINNED_ENV.items())))


__all__ = ["MARKER", "NUMERICS", "PINNED_ENV", "NumericsError", "check", "pinned_backend", "problems", "supported"]
