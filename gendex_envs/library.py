"""Where the task library lies, in a checkout and in an installed wheel: the one resolver of its folders.

The library is four folders: ``generated_tasks/`` (the committed task versions and their trust record),
``suites/`` (benchmark suites), ``datasets/`` (published dataset manifests) and ``prompts/`` (the generator's
prompt templates). In a checkout they are the top-level folders beside ``gendex_envs/``. A wheel ships them, as
tracked in git, inside the data package :data:`DATA_PACKAGE` (``site-packages/gendex_data/<folder>/``; ``setup.py``
copies them there when the wheel is built), which holds no code of its own.

The data package is deliberately not under ``gendex_envs/``: :func:`gendex_envs.guard.is_trusted` trusts every file
under the package's own folder, while committed reward modules must be trusted only when their bytes match
``generated_tasks/TRUSTED.sha256`` (:mod:`gendex_envs.trust_record`) wherever the library lies.

Every reader finds these folders through :func:`library_dir` (``registry.REPO_TASKS_DIR``,
``gendex.eval.suite.SUITES_DIR``, ``gendex.data.datasets.DATASETS_DIR``, ``generator.prompts.PROMPTS_DIR``), so "the
committed library" means the shipped one when installed. A user's own task folders still come from
``$GENDEX_TASKS_PATH`` (:mod:`gendex_envs.registry`) and are neither committed nor trusted.
"""

from __future__ import annotations

import importlib.util
from functools import cache
from pathlib import Path

DATA_PACKAGE = "gendex_data"
LIBRARY_FOLDERS = ("generated_tasks", "suites", "datasets", "prompts")
"""The folders a wheel ships (``setup.py`` lists the same ones; a test holds the two equal)."""

_SOURCE_ROOT = Path(__file__).resolve().parent.parent


def checkout_root() -> Path | None:
    """The checkout this ``gendex_envs`` was imported from (its parent folder holds ``pyproject.toml``: a clone or an
    editable install), or None for an installed copy."""
    return _SOURCE_ROOT if (_SOURCE_ROOT / "pyproject.toml").is_file() else None


@cache
def library_root() -> Path:
    """The folder holding the library's folders: the checkout when there is one, otherwise the installed
    :data:`DATA_PACKAGE` (found without importing it). With neither, the folder beside the package, whose library
    folders are then missing: their readers report that as they report an empty library."""
    checkout = checkout_root()
    if checkout is not None:
        return checkout
    spec = importlib.util.find_spec(DATA_PACKAGE)
    if spec is not None and spec.submodule_search_locations:
        return Path(next(iter(spec.submodule_search_locations))).resolve()
    return _SOURCE_ROOT


def library_dir(name: str) -> Path:
    """One of :data:`LIBRARY_FOLDERS`, in a checkout or in the installed data package."""
    if name not in LIBRARY_FOLDERS:
        raise ValueError(f"{name!r} is not a library folder (one of {', '.join(LIBRARY_FOLDERS)})")
    return library_root() / name


def installed() -> bool:
    """Whether the library is the one a wheel installed (no checkout)."""
    return checkout_root() is None and library_root() != _SOURCE_ROOT


__all__ = ["DATA_PACKAGE", "LIBRARY_FOLDERS", "checkout_root", "installed", "library_dir", "library_root"]
