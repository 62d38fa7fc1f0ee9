"""The wheel ships the task library: built once from an export of the work tree (``scripts/check_wheel.py``), its file
list is the work tree's, byte for byte, and an unpacked copy, with no checkout on the path, registers what the
checkout registers from the library it carries (issue 44, "installable tasks"). The full check, a fresh venv with
``gym.make`` + 10 steps on random ids, is the slow test at the end (and ``scripts/check_wheel.py``)."""

from __future__ import annotations

import hashlib
import importlib.util
import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from gendex_envs import library, registry

REPO = Path(__file__).resolve().parents[2]
SCRIPT = REPO / "scripts" / "check_wheel.py"
DATA = library.DATA_PACKAGE + "/"


def _script():
    spec = importlib.util.spec_from_file_location("check_wheel", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _setup_py_folders() -> tuple[str, ...]:
    import ast

    for node in ast.parse((REPO / "setup.py").read_text()).body:
        if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", "") == "LIBRARY_FOLDERS":
            return ast.literal_eval(node.value)
    raise AssertionError("setup.py has no LIBRARY_FOLDERS")


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """(the wheel, the exported files it was built from)."""
    tmp = tmp_path_factory.mktemp("wheel")
    check = _script()
    files = check.export_tree(tmp / "src")
    return check.build_wheel(tmp / "src", tmp / "dist"), files


def test_setup_and_the_resolver_name_the_same_folders():
    assert _setup_py_folders() == library.LIBRARY_FOLDERS == _script().LIBRARY_FOLDERS


def test_in_a_checkout_the_library_is_the_checkouts_folders():
    assert library.checkout_root() == REPO and not library.installed()
    assert registry.REPO_TASKS_DIR == REPO / "generated_tasks"
    from gendex.data.datasets import DATASETS_DIR
    from gendex.eval.suite import SUITES_DIR
    from generator.prompts import PROMPTS_DIR

    assert (SUITES_DIR, DATASETS_DIR, PROMPTS_DIR) == (REPO / "suites", REPO / "datasets", REPO / "prompts")
    with pytest.raises(ValueError):
        library.library_dir("leaderboard")


def test_the_wheel_holds_the_tracked_library_byte_for_byte_and_every_package_file(built):
    wheel, exported = built
    with zipfile.ZipFile(wheel) as z:
        names = [n for n in z.namelist() if ".dist-info/" not in n]
        shipped = {n[len(DATA):]: hashlib.sha256(z.read(n)).hexdigest() for n in names if n.startswith(DATA)}
    tracked = subprocess.run(["git", "ls-files", "-z", "--", *library.LIBRARY_FOLDERS], cwd=REPO,
                             capture_output=True, check=True).stdout.decode().split("\0")
    tracked = {f for f in tracked if f and (REPO / f).is_file()}
    assert set(shipped) - {"__init__.py"} == tracked
    kinds = {"task.yaml": 0, ".py": 0, "TRUSTED.sha256": 0}
    for rel in tracked:
        assert shipped[rel] == hashlib.sha256((REPO / rel).read_bytes()).hexdigest(), f"{rel} differs in the wheel"
        kinds["task.yaml"] += rel.endswith("/task.yaml")
        kinds[".py"] += rel.startswith("generated_tasks/") and rel.endswith(".py")
        kinds["TRUSTED.sha256"] += rel == "generated_tasks/TRUSTED.sha256"
    assert kinds["task.yaml"] == len(registry.discover_tasks([registry.REPO_TASKS_DIR])) and kinds[".py"] > 0
    assert kinds["TRUSTED.sha256"] == 1
    for folder in ("suites", "datasets", "prompts"):
        assert any(r.startswith(folder + "/") for r in shipped), f"no {folder}/ in the wheel"

    # the packages: every file under gendex/, gendex_envs/, generator/ (code and the data they read), nothing else
    packages = {f for f in exported if f.split("/", 1)[0] in ("gendex", "gendex_envs", "generator")}
    in_wheel = {n for n in names if not n.startswith(DATA)}
    assert in_wheel == packages, (sorted(packages - in_wheel)[:10], sorted(in_wheel - packages)[:10])


def test_an_unpacked_wheel_registers_the_checkouts_ids_from_its_own_library(built, tmp_path):
    wheel, _ = built
    site = tmp_path / "site"
    with zipfile.ZipFile(wheel) as z:
        z.extractall(site)
    code = ("import json, gymnasium as gym, gendex_envs\n"
            "from gendex_envs import library, registry, trust_record\n"
            "print(json.dumps({'ids': sorted(i for i in gym.registry if i.startswith('GenDex/')),\n"
            "  'file': gendex_envs.__file__, 'installed': library.installed(), 'root': str(library.library_root()),\n"
            "  'committed': len(registry.committed_ids()), 'trust_clean': trust_record.trust_status().clean}))\n")
    env = {k: v for k, v in os.environ.items() if not k.startswith("GENDEX_")}
    env["PYTHONPATH"] = str(site)  # ahead of the editable install's finder, which the venv appends
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    got = json.loads(done.stdout.strip().splitlines()[-1])
    assert Path(got["file"]).is_relative_to(site) and got["installed"]
    assert got["root"] == str((site / library.DATA_PACKAGE).resolve())
    checkout = sorted(i for i in registry.discover_tasks([registry.REPO_TASKS_DIR]))
    assert got["ids"] == checkout and got["committed"] == len(checkout)
    assert got["trust_clean"], "the shipped trust record does not match the shipped code"


@pytest.mark.slow
def test_a_fresh_venv_with_the_wheel_makes_and_steps_random_ids():
    done = subprocess.run([sys.executable, str(SCRIPT), "--ids", "5"], cwd=REPO, capture_output=True, text=True,
                          timeout=1200)
    assert done.returncode == 0, (done.stdout[-3000:], done.stderr[-3000:])
    summary = json.loads(done.stdout.strip().splitlines()[-1])
    assert summary["ok"] and summary["installed"]["count"] == summary["checkout_count"]
    assert len(summary["installed"]["make_and_10_steps_s"]) == 5
