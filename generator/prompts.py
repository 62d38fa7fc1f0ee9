"""Prompt templates (``prompts/``): a manifest of Jinja2 templates rendered with strict variables.

Each manifest entry names its file, the request step it serves, its sampling temperature and the exact set of
variables it uses. Rendering with a variable missing, or with one the template does not use, raises
:class:`~generator.errors.PromptError` — a silently empty field in a prompt is a bug that costs a model call.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import jinja2
import jinja2.meta
import yaml

from gendex_envs.library import library_dir
from generator.errors import PromptError

PROMPTS_DIR = library_dir("prompts")  # the checkout's prompts/, or the installed wheel's (gendex_envs.library)


@dataclass(frozen=True)
class PromptTemplate:
    name: str
    file: Path
    variables: frozenset[str]
    step: str | None = None
    temperature: float = 0.3


@functools.lru_cache(maxsize=4)
def _environment(root: Path) -> jinja2.Environment:
    return jinja2.Environment(loader=jinja2.FileSystemLoader(str(root)), undefined=jinja2.StrictUndefined,
                              keep_trailing_newline=False, autoescape=False)


@functools.lru_cache(maxsize=4)
def load_manifest(root: Path = PROMPTS_DIR) -> dict[str, PromptTemplate]:
    """Read ``manifest.yaml``; checks that each template's used variables equal the declared ones."""
    path = root / "manifest.yaml"
    if not path.is_file():
        raise PromptError(f"prompt manifest {path} does not exist")
    raw = yaml.safe_load(path.read_text())
    env = _environment(root)
    out: dict[str, PromptTemplate] = {}
    for name, entry in raw.items():
        file = root / entry["file"]
        if not file.is_file():
            raise PromptError(f"prompt {name!r}: template file {file} does not exist")
        used = jinja2.meta.find_undeclared_variables(env.parse(file.read_text()))
        declared = frozenset(entry.get("variables", []))
        if used != declared:
            raise PromptError(f"prompt {name!r} ({file.name}): template uses {sorted(used)} but the manifest declares "
                              f"{sorted(declared)}")
        out[name] = PromptTemplate(name, file, declared, entry.get("step"), float(entry.get("temperature", 0.3)))
    return out


def template(name: str, root: Path = PROMPTS_DIR) -> PromptTemplate:
    manifest = load_manifest(root)
    if name not in manifest:
        raise PromptError(f"no prompt template {name!r}; templates: {', '.join(sorted(manifest))}")
    return manifest[name]


def render(name: str, root: Path = PROMPTS_DIR, **variables: Any) -> str:
    """Render template ``name``; every declared variable must be given, and nothing else."""
    t = template(name, root)
    given = set(variables)
    missing, extra = sorted(t.variables - given), sorted(given - t.variables)
    if missing or extra:
        raise PromptError(f"prompt {name!r}: " + "; ".join(
            p for p in (f"missing variables {missing}" if missing else "",
                        f"unexpected variables {extra}" if extra else "") if p)
            + f" (it takes exactly {sorted(t.variables)})")
    try:
        return _environment(root).get_template(t.file.name).render(**variables).strip() + "\n"
    except jinja2.UndefinedError as exc:  # a variable used inside a branch the manifest check could not see
        raise PromptError(f"prompt {name!r}: {exc}") from exc
