"""Build step that ships the task library in the wheel (the project's metadata is in pyproject.toml).

``generated_tasks/``, ``suites/``, ``datasets/`` and ``prompts/`` stay top-level folders of the checkout; a wheel
carries them in the data package ``gendex_data`` (``site-packages/gendex_data/<folder>/``), where
:mod:`gendex_envs.library` finds them when no checkout is there. The files copied are the ones git tracks in those
folders (their bytes as they are in the work tree), so drafts, local renders and byte-code never ship; without git (a
build from an sdist) every file of the folders is copied, less ``__pycache__``, ``*.pyc`` and
``generated_tasks/.drafts``. An editable install copies nothing: its library is the checkout's.

``scripts/check_wheel.sh`` installs the wheel into a fresh venv and checks it from another folder;
``tests/unit/test_packaging.py`` checks the wheel's file list against git.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
DATA_PACKAGE = "gendex_data"
LIBRARY_FOLDERS = ("generated_tasks", "suites", "datasets", "prompts")  # as gendex_envs.library.LIBRARY_FOLDERS
SKIPPED_DIRS = {"__pycache__", ".drafts", ".git"}
INIT = '''"""The GenDex task library, shipped with the gendex wheel: {folders}.

Data only; read it through :mod:`gendex_envs.library` (``library_dir("generated_tasks")``), which finds this package
when gendex is installed and the checkout's folders otherwise.
"""
'''


def library_files(root: Path = ROOT) -> list[str]:
    """Paths (relative to ``root``, with ``/``) of the library's files to ship."""
    try:
        out = subprocess.run(["git", "ls-files", "-z", "--", *LIBRARY_FOLDERS], cwd=root, capture_output=True,
                             check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        out = b""
    tracked = [f for f in out.decode("utf-8").split("\0") if f]
    if tracked:
        return sorted(f for f in tracked if (root / f).is_file())  # a tracked file deleted in the work tree is gone
    files = []
    for folder in LIBRARY_FOLDERS:
        for dirpath, dirnames, filenames in os.walk(root / folder):
            dirnames[:] = sorted(d for d in dirnames if d not in SKIPPED_DIRS)
            files += [(Path(dirpath) / f).relative_to(root).as_posix() for f in filenames if not f.endswith(".pyc")]
    return sorted(files)


class BuildPyWithLibrary(build_py):
    """``build_py`` that also writes ``gendex_data/`` (the library) into the build folder."""

    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False):
            return
        dest = Path(self.build_lib) / DATA_PACKAGE
        shutil.rmtree(dest, ignore_errors=True)  # a task removed since the last build must not linger in build/
        dest.mkdir(parents=True)
        (dest / "__init__.py").write_text(INIT.format(folders=", ".join(f"{f}/" for f in LIBRARY_FOLDERS)))
        files = library_files()
        for rel in files:
            target = dest / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(ROOT / rel, target)
        self.announce(f"copied {len(files)} library files into {dest}", level=2)

    def get_outputs(self, include_bytecode: bool = True) -> list[str]:
        outputs = super().get_outputs(include_bytecode)
        if getattr(self, "editable_mode", False):
            return outputs
        dest = Path(self.build_lib) / DATA_PACKAGE
        return [*outputs, str(dest / "__init__.py"), *(str(dest / rel) for rel in library_files())]


setup(cmdclass={"build_py": BuildPyWithLibrary})
