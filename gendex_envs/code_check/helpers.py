"""Helpers shared by the static check's rule classes (:mod:`gendex_envs.code_check.checker`)."""

from __future__ import annotations

import ast
import difflib
import importlib
from dataclasses import dataclass

from gendex_envs.code_check.rules import (
    _FORBIDDEN_ATTR_REASONS,
    ALLOWED_NODE_TYPES,
    ALTERNATIVES,
)

_OP_SYMBOLS = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.FloorDiv: "//", ast.Mod: "%",
               ast.Pow: "**", ast.MatMult: "@", ast.BitOr: "|", ast.BitAnd: "&", ast.BitXor: "^", ast.LShift: "<<",
               ast.RShift: ">>"}


@dataclass(frozen=True)
class _Problem:
    line: int
    message: str
    unsafe: bool


def _snippet(source: str, node: ast.AST, limit: int = 70) -> str:
    try:
        seg = ast.get_source_segment(source, node) or ""
    except (RecursionError, ValueError, TypeError, IndexError):
        seg = ""
    seg = " ".join(seg[:2000].split())
    return seg if len(seg) <= limit else seg[: limit - 3] + "..."


def _is_dunder(name: str) -> bool:
    return name.startswith("__") and name.endswith("__") and len(name) > 4


def _attribute_problem(name: str) -> str | None:
    """Why attribute ``name`` may not be used on any object, or None."""
    if _is_dunder(name):
        return "it is a dunder attribute (Python internals)"
    if name.startswith("_"):
        return "it is private; use the public members of the env"
    if name.startswith("set_"):
        return "it is a setter; reward code only reads the state, it never changes the simulator"
    if name.endswith("_"):
        return ("it is an in-place method (it changes the tensor it is called on, which may be the env's); use the "
                f"out-of-place `{name.rstrip('_')}` and keep the result in a new variable")
    if name.startswith(("apply_", "add_", "remove_")):
        return "it changes the simulator; reward code only reads the state"
    return _FORBIDDEN_ATTR_REASONS.get(name)


_ALLOWED_NODES: tuple[type, ...] = tuple(getattr(ast, n) for n in sorted(ALLOWED_NODE_TYPES) if hasattr(ast, n))
_SCOPE_NODES = (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ListComp, ast.SetComp,
                ast.DictComp, ast.GeneratorExp, ast.ClassDef)
_FUNCTION_NODES = (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)
_SYMTABLE_NAMES = {ast.Lambda: "lambda", ast.ListComp: "listcomp", ast.SetComp: "setcomp", ast.DictComp: "dictcomp",
                   ast.GeneratorExp: "genexpr"}


def _identifiers(node: ast.AST) -> list[str]:
    """Every identifier a node names (names, attributes, parameters, aliases, keywords, pattern captures...)."""
    out: list[str] = []
    for field, value in ast.iter_fields(node):
        if isinstance(node, ast.Constant) or field in ("kind", "type_comment"):
            continue
        if isinstance(value, str):
            out.append(value)
        elif isinstance(value, list):
            out.extend(v for v in value if isinstance(v, str))
    return out


def _follow(module: str, names: list[str]) -> object:
    """``module.names...`` in the real (trusted) modules, or None."""
    try:
        obj: object = importlib.import_module(module)
        for n in names:
            obj = getattr(obj, n)
    except Exception:  # a chain that cannot be followed is judged by the other rules
        return None
    return obj


def _literal_number(node: ast.AST) -> float | None:
    try:
        value = ast.literal_eval(node)
    except (ValueError, TypeError, SyntaxError, MemoryError, RecursionError):
        return None
    return float(value) if isinstance(value, int | float) and not isinstance(value, bool) else None


def _nearest(name: str, allowed: frozenset[str] | set[str]) -> str:
    """The allowed names closest to ``name`` (for a rejection message)."""
    instead = [n for n in ALTERNATIVES.get(name, ()) if n in allowed]
    close = instead + [n for n in difflib.get_close_matches(name, sorted(allowed), n=5, cutoff=0.6)
                       if n not in instead]
    return ", ".join(f"`{n}`" for n in close) if close else "none is close to it"


def _allowed_modules_text() -> str:
    return "torch (with torch.nn.functional, torch.linalg, torch.special, torch.fft), math and " \
           "gendex_envs.reward_terms (`from gendex_envs import reward_terms as rt`)"
