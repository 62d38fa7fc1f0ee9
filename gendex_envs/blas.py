"""The same numbers on every x86-64 CPU: OpenBLAS's AVX2 (Haswell) kernels on CPUs with AVX-512 as well.

OpenBLAS picks its kernels for the CPU when it loads. On a CPU with AVX-512 it takes its SkylakeX ones, and the
solver's small linear algebra (the arm's IK, the fingers' least squares) comes out different enough that grasps do
too: on the same commit and seeds, the marker held 20 of 20 in the grasp record (a machine without AVX-512) and 1 of
4 on one with it, where every trial failed; with the AVX2 kernels it held 4 of 4, each on its first trial
(``docs/solving.md``). A procedural asset rebuilt there was not byte-identical either.

:func:`pin_kernels` sets ``OPENBLAS_CORETYPE=Haswell`` on a CPU that has AVX-512 (and AVX2), unless the variable is
set already. It must run before numpy loads OpenBLAS: importing :mod:`gendex` or :mod:`gendex_envs` first does it
(and child processes inherit it); after numpy it is too late, and a warning says so.
"""

from __future__ import annotations

import logging
import os
import sys
from pathlib import Path

log = logging.getLogger(__name__)

CORETYPE = "Haswell"


def cpu_flags(cpuinfo: Path = Path("/proc/cpuinfo")) -> frozenset[str]:
    """The CPU's feature flags (Linux; empty where unknown)."""
    try:
        for line in cpuinfo.read_text().splitlines():
            if line.startswith("flags"):
                return frozenset(line.split(":", 1)[1].split())
    except OSError:
        pass
    return frozenset()


def pin_kernels(flags: frozenset[str] | None = None) -> bool:
    """Set ``OPENBLAS_CORETYPE`` to :data:`CORETYPE` where the CPU (``flags``, default: this one's) has AVX-512 and
    AVX2 and the variable is unset; True when it set it."""
    flags = cpu_flags() if flags is None else flags
    if "OPENBLAS_CORETYPE" in os.environ or not {"avx512f", "avx2"} <= flags:
        return False
    os.environ["OPENBLAS_CORETYPE"] = CORETYPE
    if "numpy" in sys.modules:
        log.warning("numpy was imported before gendex: OpenBLAS keeps its AVX-512 kernels in this process, and "
                    "solver results may differ from other machines' (import gendex first, or set "
                    "OPENBLAS_CORETYPE=%s)", CORETYPE)
    return True
