"""One atomic writer: no module outside ``gendex_envs/atomic_io.py`` renames files into place by hand.

A hand-written temp-file-and-rename tends to miss a case ``atomic_io`` handles (the temp file left behind on error,
0600 permissions from ``mkstemp``, a temp name another writer also uses). The scan below parses every module of the
packages and tools and fails on a rename (``os.replace``, ``os.rename``, ``os.renames``, ``shutil.move``,
``Path.replace``/``Path.rename``) outside the allow-list.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCANNED = ("gendex", "gendex_envs", "generator", "scripts", "benchmarks")
WRITER = "gendex_envs/atomic_io.py"
ALLOWED: dict[tuple[str, str], str] = {
    # Publishing a task version is not a file write: a complete draft folder is renamed to the next free v<N> with a
    # no-clobber rename and retried on a race with another publisher (atomic_dir would need the version up front).
    ("gendex_envs/task_version.py", "publish"): "version allocation by no-clobber rename",
    # The LeRobot writer commits several files at once: each is staged as .<name>.tmp, a journal lists the renames,
    # and a reopened writer rolls a committed journal forward and deletes stray .tmp files. The renames are that
    # protocol's, not a single-file write.
    ("gendex/data/lerobot_files.py", "_roll_forward"): "journaled multi-file commit",
    ("gendex/data/lerobot_files.py", "_commit"): "journaled multi-file commit",
    # A pulled dataset is merged file by file into an --out folder that may hold other tasks already; the work
    # folder is complete before any file moves, and removed afterwards.
    ("gendex/data/datasets.py", "_move_into"): "merge of a finished pull into an existing folder",
}
_MODULE_RENAMES = {("os", "replace"), ("os", "rename"), ("os", "renames"), ("shutil", "move")}


def renames(source: str | bytes) -> list[tuple[int, str]]:
    """(line, enclosing function) of each rename call in ``source``."""
    found: list[tuple[int, str]] = []

    def visit(node: ast.AST, where: str) -> None:
        for child in ast.iter_child_nodes(node):
            inner = child.name if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)) else where
            if isinstance(child, ast.ImportFrom) and child.module in ("os", "shutil") and any(
                    (child.module, a.name) in _MODULE_RENAMES for a in child.names):
                found.append((child.lineno, where))  # `from os import replace` would hide the call
            if isinstance(child, ast.Call) and isinstance(child.func, ast.Attribute):
                f = child.func
                module_call = isinstance(f.value, ast.Name) and (f.value.id, f.attr) in _MODULE_RENAMES
                # Path.replace(target) / Path.rename(target): one positional argument, no keywords. str.replace
                # takes two or three; dataclasses.replace and DataFrame.rename take keywords.
                path_call = (f.attr in ("replace", "rename") and len(child.args) == 1 and not child.keywords
                             and not (isinstance(f.value, ast.Name) and f.value.id == "dataclasses"))
                if module_call or path_call:
                    found.append((child.lineno, where))
            visit(child, inner)

    visit(ast.parse(source), "<module>")
    return found


def test_no_hand_written_rename_outside_atomic_io():
    bad = []
    for top in SCANNED:
        for path in sorted((ROOT / top).rglob("*.py")):
            rel = path.relative_to(ROOT).as_posix()
            if rel == WRITER:
                continue
            bad += [f"{rel}:{line} ({fn})" for line, fn in renames(path.read_bytes()) if (rel, fn) not in ALLOWED]
    assert not bad, (f"files renamed into place by hand at {bad}: use gendex_envs.atomic_io (atomic_path, "
                     f"write_text, write_bytes, write_json, atomic_dir), or allow-list it here with the reason")


def test_the_scan_finds_each_kind_of_rename():
    src = """
import os, shutil
from os import replace
def a(tmp, path):
    os.replace(tmp, path)
    os.rename(tmp, path)
    shutil.move(tmp, path)
    tmp.replace(path)
    tmp.rename(path)
def b(text, spec):
    text.replace("a", "b")
    dataclasses.replace(spec)
    dataclasses.replace(spec, name="x")
    df.rename(columns={"a": "b"})
"""
    assert renames(src) == [(3, "<module>"), (5, "a"), (6, "a"), (7, "a"), (8, "a"), (9, "a")]


def test_the_allow_list_is_not_stale():
    """Each allow-listed function still exists and still renames (else its entry should go)."""
    for rel, fn in ALLOWED:
        assert fn in {f for _, f in renames((ROOT / rel).read_bytes())}, (rel, fn)
