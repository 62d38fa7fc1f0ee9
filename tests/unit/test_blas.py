"""OpenBLAS's kernels are pinned to AVX2 (Haswell) on CPUs with AVX-512, so the solver computes the same numbers as on
machines without it (``gendex_envs/blas.py``): on one with AVX-512 the grasp record's marker held 1 of 4 attempts it
had held on the record's machine, and a rebuilt procedural asset was not byte-identical."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from gendex_envs.blas import CORETYPE, cpu_flags, pin_kernels


@pytest.fixture
def no_coretype(monkeypatch):
    monkeypatch.delenv("OPENBLAS_CORETYPE", raising=False)


def test_an_avx512_cpu_gets_the_avx2_kernels(no_coretype):
    assert pin_kernels(frozenset({"sse2", "avx2", "avx512f"}))
    assert os.environ["OPENBLAS_CORETYPE"] == CORETYPE


@pytest.mark.parametrize("flags", [{"sse2", "avx2"}, {"sse2"}, set(), {"avx512f"}])
def test_other_cpus_keep_what_openblas_picks(no_coretype, flags):
    assert not pin_kernels(frozenset(flags))
    assert "OPENBLAS_CORETYPE" not in os.environ


def test_a_coretype_set_by_the_user_is_kept(monkeypatch):
    monkeypatch.setenv("OPENBLAS_CORETYPE", "Zen")
    assert not pin_kernels(frozenset({"avx2", "avx512f"}))
    assert os.environ["OPENBLAS_CORETYPE"] == "Zen"


def test_importing_gendex_envs_first_pins_the_kernels_numpy_loads():
    """In a new process: on this CPU, numpy's OpenBLAS runs the AVX2 kernels if the CPU has AVX-512."""
    code = ("import gendex_envs, numpy, os; from threadpoolctl import threadpool_info; "
            "print(os.environ.get('OPENBLAS_CORETYPE'), *[i.get('architecture') for i in threadpool_info() "
            "if i.get('internal_api') == 'openblas'])")
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
    coretype, *archs = out.split()
    if {"avx512f", "avx2"} <= cpu_flags():
        assert coretype == CORETYPE and archs and all(a == CORETYPE for a in archs), out
    else:
        assert coretype == "None", out
