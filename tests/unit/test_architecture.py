"""The layering of docs/architecture.md holds in the source: imports go down only, the diagram matches them, only
TaskVersion spells a task folder's file names, and no module grows past about 600 lines."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from gendex_envs.task_version import RECORDS, TaskLayout

PACKAGES = ("gendex_envs", "gendex", "generator")
UNITS = {"gendex_envs": "runtime", "gendex.solve": "solve", "gendex.data": "data", "gendex.train": "train",
         "gendex.eval": "eval", "gendex.imitation": "imitation", "gendex.gallery": "gallery", "generator": "generator",
         "gendex.fanout": "fanout", "gendex.episode_loop": "loop",
         **{f"gendex.{m}": "cli" for m in ("cli", "cli_common", "cli_dataset", "cli_bc", "cli_eval", "cli_trust",
                                           "cli_check", "cli_list", "cli_store", "cli_restyle", "check", "demo")}}
"""Import prefix -> the unit the architecture diagram draws (the longest matching prefix wins)."""
ALLOWED = {
    "runtime": set(),
    "fanout": set(),
    "loop": {"runtime"},
    "solve": {"runtime", "loop"},
    "data": {"runtime", "solve", "fanout", "loop"},
    "train": {"runtime", "solve", "fanout", "loop"},
    "generator": {"runtime", "solve", "fanout", "loop"},
    "gallery": {"runtime", "solve"},
    "eval": {"runtime", "solve", "fanout", "loop"},
    "imitation": {"runtime"},
    "cli": {"runtime", "solve", "data", "train", "generator", "gallery", "eval", "imitation", "fanout", "loop"},
}
MAX_MODULE_LINES = 650
"""'No module over about 600 lines' (docs/architecture.md); split a module before it gets here."""


def _unit(module: str) -> str | None:
    best = max((p for p in UNITS if module == p or module.startswith(p + ".")), key=len, default=None)
    return UNITS[best] if best else None


def _sources(root: Path, folders=PACKAGES) -> list[Path]:
    return sorted(p for folder in folders for p in (root / folder).rglob("*.py"))


def _module_name(root: Path, path: Path) -> str:
    return ".".join(path.relative_to(root).with_suffix("").parts).removesuffix(".__init__")


def import_edges(root: Path) -> dict[tuple[str, str], list[str]]:
    """(unit, imported unit) -> the files importing it, over every import (lazy and type-only ones included)."""
    edges: dict[tuple[str, str], list[str]] = {}
    for path in _sources(root):
        src = _unit(_module_name(root, path))
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([node.module] if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module
                     else [a.name for a in node.names] if isinstance(node, ast.Import) else [])
            for name in names:
                dst = _unit(name)
                if dst and dst != src:
                    edges.setdefault((src, dst), []).append(str(path.relative_to(root)))
    return edges


def diagram_edges(root: Path) -> set[tuple[str, str]]:
    doc = (root / "docs" / "architecture.md").read_text()
    block = re.search(r"```mermaid\n(.*?)```", doc, re.S)
    assert block is not None, "docs/architecture.md has no mermaid diagram"
    return set(re.findall(r"^\s*(\w+)\s*-->\s*(\w+)\s*$", block.group(1), re.M))


def test_imports_only_go_down_the_layers(repo_root):
    bad = {edge: files for edge, files in import_edges(repo_root).items() if edge[1] not in ALLOWED[edge[0]]}
    assert not bad, f"imports against the layering rule: {bad}"


def test_the_architecture_diagram_is_the_import_graph(repo_root):
    actual = set(import_edges(repo_root))
    drawn = diagram_edges(repo_root)
    assert drawn == actual, f"drawn but not imported: {drawn - actual}; imported but not drawn: {actual - drawn}"


def _layout_patterns() -> dict[str, re.Pattern]:
    """How each name of the task layout would appear in code: file names anywhere, folder names as path parts."""
    files = TaskLayout(".")
    names = [files.spec.name, files.reward.name, files.transcript.name, *(files.record(k).name for k in RECORDS)]
    folders = [files.stage_rewards.name, files.start_states_dir.name, files.policies.name, files.renders.name,
               files.policy_checkpoints("x").name]
    out = {n: re.compile(rf"(?<![\w.]){re.escape(n)}(?!\w)") for n in names}
    out |= {n: re.compile(rf"(^|[/\\]){re.escape(n)}([/\\]|$)") for n in folders}
    return out


# Names of the task layout that other tools' layouts also use, where a module spells that tool's folder and not ours.
FOREIGN_LAYOUT: dict[tuple[str, str], str] = {
    # lerobot's train() writes OUT/checkpoints/<step>/pretrained_model; the two scripts name that folder to find the
    # weights it wrote, never a task folder's checkpoints/.
    ("scripts/lerobot_train_pixels.py", "checkpoints"): "lerobot train()'s output layout",
    ("scripts/lerobot_act_policy.py", "checkpoints"): "lerobot train()'s output layout",
}


@pytest.mark.parametrize("folders", [PACKAGES + ("benchmarks", "scripts")])
def test_only_task_version_spells_the_task_layout(repo_root, folders):
    owner = repo_root / "gendex_envs" / "task_version.py"
    patterns = _layout_patterns()
    found = []
    for path in _sources(repo_root, folders):
        if path == owner:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                for name, pattern in patterns.items():
                    rel = str(path.relative_to(repo_root))
                    if pattern.search(node.value) and (rel, name) not in FOREIGN_LAYOUT:
                        found.append(f"{rel}:{node.lineno}: {name!r}")
    assert not found, "layout names outside TaskVersion:\n" + "\n".join(found)


def test_the_layout_search_finds_what_it_looks_for():
    patterns = _layout_patterns()
    assert patterns["task.yaml"].search("generated_tasks/X/v0/task.yaml")
    assert patterns["policies"].search("v0/policies/grasp.zip") and not patterns["policies"].search("two policies")
    assert not patterns["task.yaml"].search("mytask.yaml")


def test_no_module_is_too_long(repo_root):
    long = {str(p.relative_to(repo_root)): n for p in _sources(repo_root)
            if (n := len(p.read_text().splitlines())) > MAX_MODULE_LINES}
    assert not long, f"modules over {MAX_MODULE_LINES} lines: {long}"


def test_library_code_logs_instead_of_printing(repo_root):
    prints = [f"{p.relative_to(repo_root)}:{n.lineno}" for p in _sources(repo_root)
              for n in ast.walk(ast.parse(p.read_text()))
              if isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id == "print"]
    assert not prints, prints


def test_the_foreign_layout_list_is_not_stale(repo_root):
    """Each exempted module still spells that name (else its entry should go)."""
    patterns = _layout_patterns()
    for rel, name in FOREIGN_LAYOUT:
        strings = [n.value for n in ast.walk(ast.parse((repo_root / rel).read_text()))
                   if isinstance(n, ast.Constant) and isinstance(n.value, str)]
        assert any(patterns[name].search(s) for s in strings), f"{rel} no longer spells {name!r}: drop its entry"
