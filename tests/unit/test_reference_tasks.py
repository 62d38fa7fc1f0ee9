"""One list of the reference tasks: ``gendex_envs.registry.REFERENCE_TASKS``.

Every other place (the CLI's defaults, benchmarks, tests) imports it. A scan of the project's Python sources fails
when a tuple, list or set literal spells the three names again (bare, ``GenDex/<name>`` or ``GenDex/<name>-vN``), so
a second copy cannot drift from the first. Tables keyed by task (dicts such as the paper's numbers) are data about
each task, not the list, and are checked against it instead.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

from gendex.eval.suite import load_suite
from gendex.train.ablate import PAPER
from gendex_envs.registry import REFERENCE_TASKS, resolve_task

ROOT = Path(__file__).resolve().parents[2]
SCANNED = ("gendex", "gendex_envs", "generator", "scripts", "benchmarks", "tests")
SKIPPED = ("tests/data/",)
"""Fixture files (hostile inputs, some not even UTF-8), not code."""
HOME = "gendex_envs/registry.py"
"""The one module that defines the list."""
ALLOWED: dict[str, str] = {}
"""Files that may spell the list themselves (path -> why); none today."""
_ID = re.compile(r"(?:GenDex/)?([A-Za-z][A-Za-z0-9]*)(?:-v\d+)?")


def _spelled_lists(source: str | bytes) -> list[int]:
    """Line numbers of tuple/list/set literals whose string elements name every reference task."""
    lines = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
            names = {m.group(1) for e in node.elts if isinstance(e, ast.Constant) and isinstance(e.value, str)
                     and (m := _ID.fullmatch(e.value))}
            if set(REFERENCE_TASKS) <= names:
                lines.append(node.lineno)
    return lines


def test_no_second_definition_of_the_reference_tasks():
    found = []
    for top in SCANNED:
        for path in sorted((ROOT / top).rglob("*.py")):
            rel = path.relative_to(ROOT).as_posix()
            if rel == HOME or rel in ALLOWED or rel.startswith(SKIPPED):
                continue
            found += [f"{rel}:{line}" for line in _spelled_lists(path.read_bytes())]
    assert not found, (f"the reference tasks are spelled out again at {found}; import "
                       f"gendex_envs.registry.REFERENCE_TASKS instead")


def test_the_scan_finds_a_copy_and_the_home_module_has_one():
    assert _spelled_lists('X = ("GenDex/OpenCabinet-v0", "GenDex/PickUpBottle-v2", "PutAppleBowl")\n') == [1]
    assert _spelled_lists('X = {"OpenCabinet": 1, "PickUpBottle": 2, "PutAppleBowl": 3}\n') == []  # a table
    assert _spelled_lists('X = ["OpenCabinet", "PickUpBottle"]\n') == []
    assert len(_spelled_lists((ROOT / HOME).read_text(encoding="utf-8"))) == 1


def test_the_list_names_three_committed_tasks():
    assert len(set(REFERENCE_TASKS)) == len(REFERENCE_TASKS) == 3
    assert [resolve_task(name).name for name in REFERENCE_TASKS] == list(REFERENCE_TASKS)


def test_the_reference_suite_and_the_papers_table_cover_the_list():
    """The benchmark suite gendex-ref-v1 pins a version of each reference task (a published file with a hash, so it
    names them itself); the ablation's table of the paper's numbers has one row per reference task."""
    suite = load_suite("gendex-ref-v1")
    assert sorted(_ID.fullmatch(t).group(1) for t in suite.tasks) == sorted(REFERENCE_TASKS)
    assert sorted(PAPER) == sorted(REFERENCE_TASKS)
