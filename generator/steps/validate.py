"""Validate language-model reward code before it is committed: a static ``ast`` check, then a probe in the simulator.

Reward modules (the task's and the stages', laid out as :class:`~gendex_envs.task_version.TaskLayout` says; interface
in :mod:`gendex_envs.reward_module`) are written by a language model, so they are untrusted. Two layers keep them in
check; every rejection raises a typed error whose message is fed back to the model verbatim, so it names the line
and the construct (static) or the function, step and observed vs expected value (probe).

1. :func:`check_reward_source` parses the code and rejects anything outside a small, pure-tensor subset of Python
   (:class:`~generator.errors.UnsafeCodeError`; syntax and interface problems raise its base class
   :class:`~generator.errors.RewardCodeError`):

   * imports: only ``torch`` (and its ``torch.nn``, ``torch.nn.functional``, ``torch.linalg``, ``torch.special``,
     ``torch.fft`` submodules), ``math`` and ``gendex_envs.reward_terms`` (``from gendex_envs import reward_terms
     as rt``), plus ``from __future__ import annotations``. ``numpy`` is *not* allowed: torch covers what reward
     code needs, numpy would force GPU->host copies and brings file I/O (``np.load``, ``tofile``) and ``ctypes``
     paths that would have to be fenced off too.
   * module top level: docstring, imports, function definitions and constant assignments only (numbers, strings,
     tuples, arithmetic on them, ``math.pi``-like module constants); nothing runs at import time, so no decorators,
     and defaults are literals.
   * names: builtins only from :data:`ALLOWED_BUILTINS`; ``open``, ``exec``, ``eval``, ``compile``, ``globals``,
     ``vars``, ``setattr``, ``print``, ... are rejected (:data:`FORBIDDEN_NAMES`); ``getattr``/``hasattr`` only
     as ``getattr(obj, "literal")``, checked like ``obj.literal``.
   * attributes: no dunders (``__class__``, ``__globals__``, ...), no private ``_names``, no frame/code
     introspection (``gi_frame``, ``f_globals``, ...), no file/process/network/module names (``open``,
     ``write_text``, ``unlink``, ``os``, ``system``, ``load``, ``save``, ...) and no simulator/global-state mutators
     (``set_*``, ``step``, ``reset``, ``manual_seed``, ...): :data:`FORBIDDEN_ATTRIBUTES`. Attribute chains on
     imported modules are resolved, so ``torch.load``, ``torch.hub``, ``torch.jit``, ``torch.compile``,
     ``torch.utils.cpp_extension``, ``torch.ops``, ``torch.classes`` and ``torch.os`` (torch re-exports ``os``)
     are rejected wherever they appear, and a module may only be used as ``module.<name>`` (no aliasing it into
     a variable).
   * statements: no ``global``/``nonlocal``, classes, ``async``, ``yield``, imports inside functions, attribute
     assignment (reward functions must not change the env), or ``while True`` loops without ``break``/``return``.
   * interface: ``evaluate(env)`` and ``compute_dense_reward(env, obs, action, info)`` are required,
     ``_get_obs_extra(env, info)`` is optional, with exactly those parameter counts; ``REWARD_MAX`` if literal
     must be > 0.

2. :func:`probe_task` / :func:`probe_reward_module` run the modules in a child process (see
   :mod:`generator.steps.probe_child`) so that an infinite loop, a segfault or a memory blow-up cannot take down
   the generator: the child builds the task's env once, swaps each candidate module in, resets and steps seeded
   random actions and checks every call (``success``/``fail`` bool ``[N]`` on the env's device and never both
   true, a finite float ``[N]`` reward, finite ``[N, ...]`` observations). The parent enforces the time and memory
   limits and turns every failure into :class:`~generator.errors.RewardProbeError`.

:func:`validate_reward_module` is both layers for one module; :func:`validate_task` validates all modules of a task
and returns a JSON-able :class:`ValidationReport` instead of raising.
"""

from __future__ import annotations

import ast
import builtins
import dataclasses
import importlib
import json
import logging
import math
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
import types
from dataclasses import dataclass, field
from pathlib import Path

from gendex_envs.errors import GenDexError, TaskNotFoundError
from gendex_envs.task_version import TaskLayout
from generator.errors import (
    GeneratorError,
    RewardCodeError,
    RewardProbeError,
    UnsafeCodeError,
)

log = logging.getLogger(__name__)

# ---------------------------------------------------------------------------------------------------- the rules
ALLOWED_MODULES = frozenset({
    "torch", "torch.nn", "torch.nn.functional", "torch.linalg", "torch.special", "torch.fft",
    "math", "gendex_envs.reward_terms",
})
"""Modules reward code may import and reach through attributes (everything else, numpy included, is rejected)."""
ALLOWED_PACKAGES = frozenset({"gendex_envs"})
"""Packages that may appear in ``from <package> import <allowed module>`` (only to reach an allowed module)."""

REQUIRED_FUNCTIONS = {"evaluate": ("env",), "compute_dense_reward": ("env", "obs", "action", "info")}
OPTIONAL_FUNCTIONS = {"_get_obs_extra": ("env", "info")}

ALLOWED_BUILTINS = frozenset({
    "abs", "all", "any", "bool", "dict", "divmod", "enumerate", "filter", "float", "frozenset", "int",
    "isinstance", "len", "list", "map", "max", "min", "pow", "range", "reversed", "round", "set", "slice", "sorted",
    "str", "sum", "tuple", "zip", "getattr", "hasattr",
    "ArithmeticError", "AssertionError", "Exception", "IndexError", "KeyError", "LookupError",
    "NotImplementedError", "RuntimeError", "TypeError", "ValueError", "ZeroDivisionError",
})
"""Builtins reward code may use (``getattr``/``hasattr`` only with a literal attribute name)."""

FORBIDDEN_NAMES = frozenset({
    "open", "exec", "eval", "compile", "__import__", "globals", "locals", "vars", "input", "breakpoint", "exit",
    "quit", "memoryview", "help", "setattr", "delattr", "print", "__builtins__",
})
"""Names that may not appear at all, not even as a local variable (so no scope trick can reach the builtin).

Other builtins outside :data:`ALLOWED_BUILTINS` are rejected when used unbound (``type(x)``, ``dir()``)."""

_FORBIDDEN_ATTR_REASONS: dict[str, str] = {}
for _names, _why in (
    (("open", "read_text", "write_text", "read_bytes", "write_bytes", "unlink", "rmdir", "mkdir", "rename",
      "replace", "touch", "chmod", "symlink_to", "hardlink_to", "tofile", "fromfile", "from_file", "dump", "dumps",
      "load", "loads", "save", "savez", "iterdir", "glob", "rglob", "expanduser", "home", "cwd", "write", "read"),
     "it reads or writes files"),
    (("os", "sys", "subprocess", "shutil", "socket", "ctypes", "importlib", "builtins", "pickle", "marshal",
      "pathlib", "io", "tempfile", "multiprocessing", "threading", "signal", "inspect", "gc", "types", "code",
      "runpy", "pty", "urllib", "http", "posix", "mmap", "resource", "platform", "sysconfig", "site",
      "fcntl", "asyncio", "concurrent", "webbrowser", "requests", "zipfile", "tarfile", "sqlite3", "json", "yaml"),
     "it names a module reward code may not use"),
    (("numpy", "np"), "it leaves torch (numpy is not allowed: keep tensors on env.device)"),
    (("system", "popen", "spawn", "spawnv", "execv", "execve", "execl", "fork", "kill", "exec", "eval", "compile",
      "hub", "jit", "ops", "classes", "utils", "cpp_extension", "package", "library", "distributed", "backends",
      "cuda", "mps", "xpu", "fx", "export", "onnx", "profiler", "testing"),
     "it loads or runs code, or reaches the process, the network or devices outside the env"),
    (("gi_frame", "gi_code", "gi_yieldfrom", "cr_frame", "cr_code", "cr_await", "ag_frame", "ag_code",
      "ag_await", "f_globals", "f_locals", "f_builtins", "f_back", "f_code", "f_trace", "tb_frame", "tb_next",
      "co_code", "co_consts", "co_names", "func_globals", "func_code", "mro", "format", "format_map"),
     "it introspects frames, code or classes"),
    (("step", "reset", "close", "reconfigure", "render", "render_human", "render_rgb_array", "render_views",
      "render_sensors", "manual_seed", "seed", "use_deterministic_algorithms", "share_memory_", "register_hook",
      "register_forward_hook", "requires_grad_", "backward"),
     "it changes the simulator or global state; reward code only reads the state"),
):
    for _n in _names:
        _FORBIDDEN_ATTR_REASONS[_n] = _why
FORBIDDEN_ATTRIBUTES = frozenset(_FORBIDDEN_ATTR_REASONS)
"""Attribute names rejected on any object (plus dunders, ``_private`` names and the ``set_*`` prefix)."""

MAX_SOURCE_CHARS = 100_000
"""Longer sources are rejected unparsed (reward modules are a few dozen lines)."""
MAX_LISTED_PROBLEMS = 20

_FEEDBACK_HINT = ("reward code is pure tensor arithmetic on env state: import only torch, math and "
                  "gendex_envs.reward_terms, read env members, return tensors")


@dataclass(frozen=True)
class _Problem:
    line: int
    message: str
    unsafe: bool


def _snippet(source: str, node: ast.AST, limit: int = 70) -> str:
    seg = ast.get_source_segment(source, node) or ""
    seg = " ".join(seg.split())
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
    return _FORBIDDEN_ATTR_REASONS.get(name)


_NAMED_BINDERS = (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.ExceptHandler, ast.MatchAs, ast.MatchStar)


class _Checker:
    """One pass over a parsed module; collects every problem (iterative: deep expressions cannot overflow)."""

    def __init__(self, source: str, tree: ast.Module):
        self.source = source
        self.tree = tree
        self.problems: list[_Problem] = []
        self.parent: dict[ast.AST, ast.AST] = {}
        for node in ast.walk(tree):
            for child in ast.iter_child_nodes(node):
                self.parent[child] = node
        self.module_aliases: dict[str, str] = {}
        """Name bound by an import -> the dotted module it names (only for names that are modules)."""
        self.bound: set[str] = set()
        """Every name bound anywhere in the module (any scope)."""

    # -------------------------------------------------------------- helpers
    def add(self, node: ast.AST, message: str, unsafe: bool = True) -> None:
        self.problems.append(_Problem(getattr(node, "lineno", 0), message, unsafe))

    def in_function(self, node: ast.AST) -> bool:
        p = self.parent.get(node)
        while p is not None:
            if isinstance(p, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda):
                return True
            p = self.parent.get(p)
        return False

    # -------------------------------------------------------------- entry
    def run(self) -> list[_Problem]:
        self.collect_bindings()
        self.check_top_level()
        for node in ast.walk(self.tree):
            self.check_node(node)
        self.check_interface()
        return self.problems

    def collect_bindings(self) -> None:
        for node in ast.walk(self.tree):
            if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store | ast.Del):
                self.bound.add(node.id)
            elif isinstance(node, ast.arg):
                self.bound.add(node.arg)
            elif isinstance(node, _NAMED_BINDERS) and node.name:  # def/class names, `except E as x`, match captures
                self.bound.add(node.name)
            elif isinstance(node, ast.MatchMapping) and node.rest:
                self.bound.add(node.rest)
            elif isinstance(node, ast.Import | ast.ImportFrom):
                for a in node.names:
                    self.bound.add((a.asname or a.name).split(".")[0])

    # -------------------------------------------------------------- top level
    def check_top_level(self) -> None:
        seen: dict[str, int] = {}

        def bind(name: str, node: ast.AST) -> None:
            if name in seen:
                self.add(node, f"`{name}` is bound twice at the top level (lines {seen[name]} and {node.lineno}); "
                         "each module-level name must be defined once", unsafe=False)
            else:
                seen[name] = node.lineno

        for stmt in self.tree.body:
            if isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Constant) and isinstance(stmt.value.value,
                                                                                                 str):
                continue  # docstring / string comment
            if isinstance(stmt, ast.Import):
                self.check_import(stmt)
                for a in stmt.names:
                    name = a.asname or a.name.split(".")[0]
                    if a.asname or name not in self.module_aliases or name not in seen:
                        bind(name, stmt)  # `import torch` then `import torch.nn` both bind `torch`: fine
            elif isinstance(stmt, ast.ImportFrom):
                self.check_import_from(stmt)
                for a in stmt.names:
                    if stmt.module != "__future__":
                        bind(a.asname or a.name, stmt)
            elif isinstance(stmt, ast.FunctionDef):
                bind(stmt.name, stmt)
            elif isinstance(stmt, ast.Assign | ast.AnnAssign):
                targets = stmt.targets if isinstance(stmt, ast.Assign) else [stmt.target]
                names = []
                for t in targets:
                    elts = t.elts if isinstance(t, ast.Tuple) else [t]
                    for e in elts:
                        if isinstance(e, ast.Name):
                            names.append(e.id)
                        else:
                            self.add(stmt, f"top-level assignment `{_snippet(self.source, stmt)}` may only bind "
                                     "plain names (constants such as `LIFT_M = 0.1`)")
                for n in names:
                    bind(n, stmt)
                if stmt.value is None:
                    self.add(stmt, f"top-level annotation `{_snippet(self.source, stmt)}` needs a constant value")
                elif not self.is_constant_expr(stmt.value):
                    self.add(stmt, f"top-level assignment `{_snippet(self.source, stmt)}` is not a constant: the "
                             "top level may only assign numbers, strings, tuples of them and arithmetic on them "
                             "(e.g. `LIFT_M = 0.1`, `ANGLE = math.pi / 4`); compute everything else inside the "
                             "functions")
            elif isinstance(stmt, ast.AsyncFunctionDef | ast.ClassDef):
                pass  # reported by check_node
            else:
                self.add(stmt, f"top-level statement `{_snippet(self.source, stmt)}` runs code at import time; the "
                         "top level may only hold a docstring, imports, function definitions and constant "
                         "assignments")

    def is_constant_expr(self, node: ast.AST) -> bool:
        """Numbers, strings, booleans, None, names, tuples, arithmetic and allowed-module attributes (no calls)."""
        if isinstance(node, ast.Constant):
            return isinstance(node.value, int | float | str | bool | type(None))
        if isinstance(node, ast.Name):  # another constant (`2 * LIFT_M`, `pi`); the name rules apply as well
            return True
        if isinstance(node, ast.Tuple):
            return all(self.is_constant_expr(e) for e in node.elts)
        if isinstance(node, ast.UnaryOp):
            return self.is_constant_expr(node.operand)
        if isinstance(node, ast.BinOp):
            return self.is_constant_expr(node.left) and self.is_constant_expr(node.right)
        if isinstance(node, ast.Attribute):  # math.pi, torch.float32: resolved and checked by check_attribute
            base = node
            while isinstance(base, ast.Attribute):
                base = base.value
            return isinstance(base, ast.Name) and base.id in self.module_aliases
        return False

    def check_import(self, stmt: ast.Import) -> None:
        for a in stmt.names:
            if a.asname and (a.asname in FORBIDDEN_NAMES or _is_dunder(a.asname)):
                self.add(stmt, f"`import ... as {a.asname}`: the name `{a.asname}` may not be used in reward code")
            if a.name not in ALLOWED_MODULES:
                self.add(stmt, f"`import {a.name}` is not allowed: reward code may import only "
                         f"{_allowed_modules_text()}")
                continue
            if a.asname:
                self.module_aliases[a.asname] = a.name
            else:
                self.module_aliases[a.name.split(".")[0]] = a.name.split(".")[0]

    def check_import_from(self, stmt: ast.ImportFrom) -> None:
        mod = stmt.module or ""
        if stmt.level:
            self.add(stmt, f"relative import `{_snippet(self.source, stmt)}` is not allowed: reward code may import "
                     f"only {_allowed_modules_text()}")
            return
        if mod == "__future__":
            if any(a.name != "annotations" for a in stmt.names):
                self.add(stmt, "only `from __future__ import annotations` is allowed")
            return
        if mod not in ALLOWED_MODULES and mod not in ALLOWED_PACKAGES:
            self.add(stmt, f"`from {mod} import ...` is not allowed: reward code may import only "
                     f"{_allowed_modules_text()}")
            return
        for a in stmt.names:
            if a.asname and (a.asname in FORBIDDEN_NAMES or _is_dunder(a.asname)):
                self.add(stmt, f"`import ... as {a.asname}`: the name `{a.asname}` may not be used in reward code")
            if a.name == "*":
                self.add(stmt, f"`from {mod} import *` is not allowed: import the module and use `{mod}.<name>`")
                continue
            full = f"{mod}.{a.name}"
            if full in ALLOWED_MODULES:
                self.module_aliases[a.asname or a.name] = full
                continue
            if mod in ALLOWED_PACKAGES:
                self.add(stmt, f"`from {mod} import {a.name}` is not allowed: reward code may import only "
                         f"{_allowed_modules_text()}")
                continue
            why = _attribute_problem(a.name)
            if why:
                self.add(stmt, f"`from {mod} import {a.name}` is not allowed: {why}")
                continue
            obj = self.resolve_chain(stmt, mod, [a.name])
            if isinstance(obj, types.ModuleType):  # e.g. `from gendex_envs.reward_terms import torch`
                self.module_aliases[a.asname or a.name] = obj.__name__

    # -------------------------------------------------------------- every node
    def check_node(self, node: ast.AST) -> None:
        src = self.source
        if isinstance(node, ast.Import | ast.ImportFrom) and (self.in_function(node) or
                                                             self.parent.get(node) is not self.tree):
            self.add(node, f"`{_snippet(src, node)}`: imports belong at the top of the module, not inside "
                     "functions or blocks")
        elif isinstance(node, ast.Global | ast.Nonlocal):
            self.add(node, f"`{_snippet(src, node)}`: global/nonlocal statements are not allowed; reward functions "
                     "keep no state between calls")
        elif isinstance(node, ast.ClassDef):
            self.add(node, f"class `{node.name}` is not allowed: reward code defines plain functions only")
        elif isinstance(node, ast.AsyncFunctionDef | ast.AsyncFor | ast.AsyncWith | ast.Await):
            self.add(node, "async code is not allowed in reward modules")
        elif isinstance(node, ast.Yield | ast.YieldFrom):
            self.add(node, f"`{_snippet(src, node)}`: reward functions must return their result, not yield")
        elif isinstance(node, ast.FunctionDef | ast.Lambda):
            self.check_function(node)
        elif isinstance(node, ast.Name):
            self.check_name(node)
        elif isinstance(node, ast.Attribute):
            self.check_attribute(node)
        elif isinstance(node, ast.Call):
            self.check_call(node)
        elif isinstance(node, ast.Assign | ast.AugAssign | ast.AnnAssign | ast.Delete):
            if isinstance(node, ast.AnnAssign):
                self.check_annotation(node.annotation)
            targets = node.targets if isinstance(node, ast.Assign | ast.Delete) else [node.target]
            for t in targets:
                for sub in ast.walk(t):
                    if isinstance(sub, ast.Attribute) and isinstance(sub.ctx, ast.Store | ast.Del):
                        self.add(node, f"`{_snippet(src, node)}` changes an attribute; reward code must not "
                                 "modify the env or other objects (compute into local variables instead)")
        elif isinstance(node, ast.While):
            self.check_while(node)
        elif isinstance(node, ast.arg | ast.ExceptHandler | ast.MatchAs | ast.MatchStar):
            name = node.arg if isinstance(node, ast.arg) else node.name
            if name and (name in FORBIDDEN_NAMES or _is_dunder(name)):
                self.add(node, f"the name `{name}` may not be used in reward code")
            if name and name in self.module_aliases:
                self.add(node, f"`{name}` rebinds the imported module `{self.module_aliases[name]}`; pick "
                         "another name")

    def check_function(self, node: ast.FunctionDef | ast.Lambda) -> None:
        args = node.args
        if isinstance(node, ast.FunctionDef):
            if node.decorator_list:
                self.add(node.decorator_list[0], f"decorator on `{node.name}` is not allowed: decorators run at "
                         "import time")
            if _is_dunder(node.name) or node.name in FORBIDDEN_NAMES:
                self.add(node, f"function name `{node.name}` is not allowed")
            if node.name in self.module_aliases:
                self.add(node, f"function `{node.name}` rebinds the imported module "
                         f"`{self.module_aliases[node.name]}`")
            annotations = [a.annotation for a in (*args.posonlyargs, *args.args, *args.kwonlyargs,
                                                  args.vararg, args.kwarg) if a is not None and a.annotation]
            if node.returns is not None:
                annotations.append(node.returns)
            for ann in annotations:
                self.check_annotation(ann)
        what = f"`{node.name}`" if isinstance(node, ast.FunctionDef) else "the lambda"
        for d in [*args.defaults, *[d for d in args.kw_defaults if d is not None]]:
            if not self.is_constant_expr(d):
                self.add(d, f"default value `{_snippet(self.source, d)}` of {what} must be a literal constant "
                         "(defaults are evaluated at import time)")

    def check_annotation(self, ann: ast.AST) -> None:
        for sub in ast.walk(ann):
            if not isinstance(sub, ast.Name | ast.Attribute | ast.Subscript | ast.Constant | ast.Tuple | ast.List |
                              ast.BinOp | ast.BitOr | ast.Load):
                self.add(ann, f"annotation `{_snippet(self.source, ann)}` must be a plain type (names, subscripts, "
                         "`|`): it is evaluated at import time")
                return

    def check_name(self, node: ast.Name) -> None:
        name = node.id
        if name in FORBIDDEN_NAMES or _is_dunder(name):
            self.add(node, f"`{name}` is not allowed in reward code ({_FEEDBACK_HINT})")
            return
        if name in ("getattr", "hasattr") and isinstance(node.ctx, ast.Load):
            call = self.parent.get(node)
            if not (isinstance(call, ast.Call) and call.func is node):
                self.add(node, f"`{name}` may only be called directly, as `{name}(obj, \"attribute\")`")
            return
        if isinstance(node.ctx, ast.Load) and name in self.module_aliases:
            parent = self.parent.get(node)
            ok = isinstance(parent, ast.Attribute) and parent.value is node
            ok = ok or (isinstance(parent, ast.Call) and isinstance(parent.func, ast.Name) and
                        parent.func.id in ("getattr", "hasattr") and parent.args and parent.args[0] is node)
            if not ok:
                self.add(node, f"the module `{name}` may only be used as `{name}.<name>` (line {node.lineno}: "
                         f"`{_snippet(self.source, parent or node)}`), not passed around or stored")
            return
        if isinstance(node.ctx, ast.Store) and name in self.module_aliases and self.in_function(node):
            self.add(node, f"`{name}` rebinds the imported module `{self.module_aliases[name]}`; pick another name")
            return
        if isinstance(node.ctx, ast.Load) and name not in self.bound and name not in ALLOWED_BUILTINS:
            if hasattr(builtins, name):
                self.add(node, f"the builtin `{name}` is not allowed in reward code; allowed builtins: "
                         f"{', '.join(sorted(ALLOWED_BUILTINS))}")
            else:
                self.add(node, f"name `{name}` is not defined (line {node.lineno}: "
                         f"`{_snippet(self.source, self.parent.get(node, node))}`)", unsafe=False)

    def attr_chain(self, node: ast.Attribute) -> tuple[str | None, list[str]]:
        """(module alias at the root or None, attribute names from the root outwards) of ``a.b.c``."""
        names = []
        cur: ast.AST = node
        while isinstance(cur, ast.Attribute):
            names.append(cur.attr)
            cur = cur.value
        names.reverse()
        root = cur.id if isinstance(cur, ast.Name) and cur.id in self.module_aliases else None
        return root, names

    def check_attribute(self, node: ast.Attribute) -> None:
        why = _attribute_problem(node.attr)
        if why:
            self.add(node, f"attribute `.{node.attr}` in `{_snippet(self.source, node)}` is not allowed: {why}")
            return
        if isinstance(self.parent.get(node), ast.Attribute):
            return  # the outermost attribute of a chain resolves the whole chain
        root, names = self.attr_chain(node)
        if root is not None and not any(_attribute_problem(n) for n in names):
            self.resolve_chain(node, self.module_aliases[root], names, shown=root)

    def resolve_chain(self, node: ast.AST, module: str, names: list[str], shown: str | None = None) -> object:
        """Follow ``module.names...`` in the real (trusted) modules; reject other modules and unknown attributes.

        Returns the object reached, or None when the chain was rejected or could not be followed.
        """
        shown = shown or module
        try:
            obj = importlib.import_module(module)
        except ImportError:  # pragma: no cover - allowed modules are installed
            return None
        path = shown
        for n in names:
            path = f"{path}.{n}"
            try:
                nxt = getattr(obj, n)
            except AttributeError:
                if isinstance(obj, types.ModuleType):
                    self.add(node, f"`{path}` does not exist (module `{obj.__name__}` has no attribute `{n}`)",
                             unsafe=False)
                return None
            except Exception:
                return None
            if isinstance(nxt, types.ModuleType) and nxt.__name__ not in ALLOWED_MODULES:
                self.add(node, f"`{path}` is the module `{nxt.__name__}`, which reward code may not use; allowed "
                         f"modules: {_allowed_modules_text()}")
                return None
            obj = nxt
        return obj

    def check_call(self, node: ast.Call) -> None:
        if not isinstance(node.func, ast.Name) or node.func.id not in ("getattr", "hasattr"):
            return
        fn = node.func.id
        if len(node.args) < 2 or not (isinstance(node.args[1], ast.Constant) and isinstance(node.args[1].value,
                                                                                             str)):
            self.add(node, f"`{_snippet(self.source, node)}`: {fn} needs a literal attribute name, e.g. "
                     f"`{fn}(env, \"goal_pos\")`")
            return
        name = node.args[1].value
        why = _attribute_problem(name)
        if why:
            self.add(node, f"`{_snippet(self.source, node)}` is not allowed: `{name}`: {why}")
            return
        first = node.args[0]
        if isinstance(first, ast.Name) and first.id in self.module_aliases:
            self.resolve_chain(node, self.module_aliases[first.id], [name], shown=first.id)

    def check_while(self, node: ast.While) -> None:
        test = node.test
        if not (isinstance(test, ast.Constant) and test.value):
            return
        stack: list[tuple[ast.AST, bool]] = [(s, False) for s in node.body]  # (node, inside a nested loop)
        while stack:
            cur, nested = stack.pop()
            if isinstance(cur, ast.Return | ast.Raise) or (isinstance(cur, ast.Break) and not nested):
                return
            if isinstance(cur, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda | ast.ClassDef):
                continue
            inner = nested or isinstance(cur, ast.For | ast.While | ast.AsyncFor)
            stack.extend((c, inner) for c in ast.iter_child_nodes(cur))
        self.add(node, f"`{_snippet(self.source, node)}` loops forever: it has no break, return or raise; reward "
                 "functions must finish quickly (vectorise over envs instead of looping)")

    # -------------------------------------------------------------- interface
    def check_interface(self) -> None:
        defs = {s.name: s for s in self.tree.body if isinstance(s, ast.FunctionDef)}
        for name, params in {**REQUIRED_FUNCTIONS, **OPTIONAL_FUNCTIONS}.items():
            fn = defs.get(name)
            signature = f"{name}({', '.join(params)})"
            if fn is None:
                if name in REQUIRED_FUNCTIONS:
                    self.add(self.tree, f"the module defines no top-level function `{signature}`; required: "
                             + ", ".join(f"`{n}({', '.join(p)})`" for n, p in REQUIRED_FUNCTIONS.items()),
                             unsafe=False)
                continue
            a = fn.args
            positional = [x.arg for x in (*a.posonlyargs, *a.args)]
            problems = []
            if len(positional) != len(params):
                problems.append(f"it takes {len(positional)} positional parameter(s) ({', '.join(positional)})")
            if a.vararg or a.kwarg:
                problems.append("it has *args/**kwargs")
            if any(d is None for d in a.kw_defaults):
                problems.append("it has required keyword-only parameters")
            if problems:
                self.add(fn, f"`{name}` must be defined as `def {signature}:` with exactly {len(params)} "
                         f"parameter(s), but {' and '.join(problems)}", unsafe=False)
        for stmt in self.tree.body:
            targets = stmt.targets if isinstance(stmt, ast.Assign) else [stmt.target] if isinstance(
                stmt, ast.AnnAssign) else []
            if any(isinstance(t, ast.Name) and t.id == "REWARD_MAX" for t in targets) and stmt.value is not None:
                value = _literal_number(stmt.value)
                if value is not None and not (math.isfinite(value) and value > 0):
                    self.add(stmt, f"REWARD_MAX = {value} must be a finite number > 0 (the upper bound of the "
                             "dense reward)", unsafe=False)


def _literal_number(node: ast.AST) -> float | None:
    try:
        value = ast.literal_eval(node)
    except (ValueError, TypeError, SyntaxError, MemoryError, RecursionError):
        return None
    return float(value) if isinstance(value, int | float) and not isinstance(value, bool) else None


def _allowed_modules_text() -> str:
    return "torch (with torch.nn.functional, torch.linalg, torch.special, torch.fft), math and " \
           "gendex_envs.reward_terms (`from gendex_envs import reward_terms as rt`)"


def check_reward_source(source: str, filename: str = "<reward module>") -> None:
    """Statically check reward module ``source``; returns None when it may be run.

    Raises :class:`~generator.errors.UnsafeCodeError` when any unsafe construct is present, else
    :class:`~generator.errors.RewardCodeError` for syntax errors, undefined names and interface problems. The
    message lists every problem found (``line N: ...``), each naming the construct and what is allowed instead.
    """
    if not isinstance(source, str):
        raise RewardCodeError(f"{filename}: reward source must be text, got {type(source).__name__}")
    if len(source) > MAX_SOURCE_CHARS:
        raise RewardCodeError(f"{filename}: {len(source)} characters is too long for a reward module (limit "
                              f"{MAX_SOURCE_CHARS}); keep it to the reward functions")
    try:
        tree = ast.parse(source, filename=filename, type_comments=False)
    except SyntaxError as exc:
        where = f"line {exc.lineno}" + (f", column {exc.offset}" if exc.offset else "")
        text = f": `{exc.text.strip()}`" if exc.text and exc.text.strip() else ""
        raise RewardCodeError(f"{filename}: syntax error at {where}{text}: {exc.msg}") from None
    except (ValueError, RecursionError, MemoryError) as exc:
        raise RewardCodeError(f"{filename}: the source cannot be parsed: {type(exc).__name__}: {exc}") from None
    try:
        problems = _Checker(source, tree).run()
    except RecursionError:
        raise UnsafeCodeError(f"{filename}: expressions are nested too deeply to check; simplify the code") from None
    if not problems:
        return
    unique = sorted({(p.line, p.message): p for p in problems}.values(), key=lambda p: p.line)
    unsafe = any(p.unsafe for p in unique)
    lines = [f"- line {p.line}: {p.message}" if p.line else f"- {p.message}" for p in unique[:MAX_LISTED_PROBLEMS]]
    if len(unique) > MAX_LISTED_PROBLEMS:
        lines.append(f"- ... and {len(unique) - MAX_LISTED_PROBLEMS} more")
    head = f"{filename} was rejected ({len(unique)} problem{'s' if len(unique) > 1 else ''}):"
    error = UnsafeCodeError if unsafe else RewardCodeError
    raise error("\n".join([head, *lines]))


def check_reward_file(path: str | Path, filename: str | None = None) -> None:
    """:func:`check_reward_source` on a file (``filename`` defaults to the file's name)."""
    path = Path(path)
    name = filename or path.name
    if not path.is_file():
        raise FileNotFoundError(f"reward module {path} does not exist")
    try:
        source = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise RewardCodeError(f"{name}: not valid UTF-8 text ({exc})") from None
    check_reward_source(source, name)


# ---------------------------------------------------------------------------------------------------- the probe
DEFAULT_STEPS = 20
DEFAULT_TIMEOUT_S = 60.0
DEFAULT_MEMORY_LIMIT_MB = 4096
DEFAULT_STARTUP_TIMEOUT_S = 300.0
"""Time allowed to import the simulator and build the env (not charged to any module)."""
_POLL_S = 0.05
_STACK_WAIT_S = 2.0
_FRAME_RE = re.compile(r'File "(?P<file>[^"]+)", line (?P<line>\d+) in (?P<fn>\S+)')


@dataclass
class ProbeReport:
    """What probing one reward module observed (JSON-able with :func:`dataclasses.asdict`)."""

    module: str
    """The module's path relative to the task folder (as :meth:`TaskLayout.relative` shows it)."""
    path: str
    steps: int
    """Random-action steps run after the reset."""
    num_envs: int
    reward_min: float
    reward_max: float
    reward_mean: float
    success_rate: float
    """Fraction of (step, env) samples, the reset included, where ``success`` was True."""
    fail_rate: float
    obs_extra: dict[str, list[int]]
    """Shape per env of each ``_get_obs_extra`` entry."""
    wall_s: float
    """Seconds to import, reset and step the module in the probe process."""
    warnings: list[str] = field(default_factory=list)
    """Suspicious but allowed observations (reward above REWARD_MAX, constant reward, warnings raised, ...)."""


@dataclass
class ModuleOutcome:
    """Validation outcome of one module."""

    module: str
    ok: bool
    failed_at: str | None = None
    """``static`` or ``probe`` when rejected."""
    error_type: str | None = None
    """Class name of the error: ``UnsafeCodeError``, ``RewardCodeError`` or ``RewardProbeError``."""
    error: str | None = None
    """The error message, ready to be fed back to the model."""
    probe: ProbeReport | None = None


@dataclass
class ValidationReport:
    """Outcome of validating every reward module of a task (JSON-able with :func:`dataclasses.asdict`)."""

    task_dir: str
    ok: bool
    modules: list[ModuleOutcome]
    steps: int
    seed: int
    wall_s: float

    def failures(self) -> list[ModuleOutcome]:
        return [m for m in self.modules if not m.ok]

    def raise_first(self) -> None:
        """Raise the first module's error again, with its type (no-op when every module passed)."""
        for m in self.failures():
            cls = {"UnsafeCodeError": UnsafeCodeError, "RewardProbeError": RewardProbeError}.get(
                m.error_type or "", RewardCodeError)
            raise cls(m.error)

    def to_json(self) -> str:
        return json.dumps(dataclasses.asdict(self), indent=2, allow_nan=True)


def task_reward_modules(task_dir: str | Path) -> list[Path]:
    """The reward modules of a task folder: the task's, then the stages' (sorted)."""
    return TaskLayout(task_dir).reward_modules()


def _display(task_dir: Path, module: Path) -> str:
    shown = TaskLayout(task_dir).relative(module)
    return shown if not Path(shown).is_absolute() else module.name


def _when(step: int | None) -> str:
    if step is None:
        return "while importing it"
    return "right after reset (step 0)" if step == 0 else f"at step {step}"


def _source_line(path: Path, line: int) -> str:
    try:
        return path.read_text(encoding="utf-8").splitlines()[line - 1].strip()
    except (OSError, IndexError, UnicodeDecodeError):
        return ""


def _stack_location(log_text: str, module: Path) -> str:
    """`` at line N (`code`)`` from the newest faulthandler dump's innermost frame in ``module`` ('' if none)."""
    target = module.resolve()
    for m in _FRAME_RE.finditer(log_text):  # frames come most recent first
        try:
            if Path(m["file"]).resolve() == target:
                code = _source_line(target, int(m["line"]))
                return f" at line {m['line']}" + (f" (`{code}`)" if code else "") + f" in {m['fn']}"
        except OSError:
            continue
    return ""


def _rss_kb(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return 0


def _setup_error(task_dir: Path, record: dict) -> GenDexError:
    """The env could not be built: not the reward's fault; keep GenDex's own error type where there is one."""
    import gendex_envs.errors as gerr

    cls = getattr(gerr, record.get("type", ""), None)
    text = f"the reward probe could not build the env of {task_dir}: {record.get('type')}: {record.get('message')}"
    if isinstance(cls, type) and issubclass(cls, GenDexError):
        return cls(text)
    return GeneratorError(text + "\n" + record.get("traceback", ""))


class _Child:
    """One probe process over ``modules``; :meth:`run` returns ``{index: ProbeReport | RewardCodeError}``."""

    def __init__(self, task_dir: Path, modules: list[Path], displays: list[str], *, steps: int, timeout_s: float,
                 seed: int, num_envs: int, sim_backend: str, memory_limit_mb: int | None, startup_timeout_s: float,
                 stop_on_error: bool, workdir: Path):
        self.task_dir, self.modules, self.displays = task_dir, modules, displays
        self.timeout_s, self.memory_limit_mb, self.startup_timeout_s = timeout_s, memory_limit_mb, startup_timeout_s
        self.workdir = workdir
        self.progress_path = workdir / "progress.jsonl"
        self.log_path = workdir / "child.log"
        layout = TaskLayout(task_dir)
        self.job = {"spec": str(layout.spec), "modules": [str(m) for m in modules], "displays": displays,
                    "stages": [layout.module_stage(m) for m in modules],
                    "steps": steps, "seed": seed, "num_envs": num_envs, "sim_backend": sim_backend,
                    "memory_limit_mb": memory_limit_mb, "stop_on_error": stop_on_error,
                    "progress": str(self.progress_path)}
        self.results: dict[int, ProbeReport | RewardCodeError] = {}
        self.current: int | None = None
        self.started_at = 0.0
        self.last_call: tuple[str | None, int | None] = (None, None)
        self.ready = False
        self.baseline_rss_kb = 0

    def run(self) -> dict[int, ProbeReport | RewardCodeError]:
        job_path = self.workdir / "job.json"
        job_path.write_text(json.dumps(self.job), encoding="utf-8")
        self.progress_path.write_text("", encoding="utf-8")
        env = dict(os.environ)
        root = str(Path(__file__).resolve().parents[2])  # the checkout holding generator/ and gendex_envs/
        env["PYTHONPATH"] = os.pathsep.join([root, *[p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p]])
        with open(self.log_path, "wb") as logf:
            proc = subprocess.Popen([sys.executable, "-m", "generator.steps.probe_child", str(job_path)],
                                    stdin=subprocess.DEVNULL, stdout=logf, stderr=subprocess.STDOUT, env=env,
                                    start_new_session=True)
        try:
            self._watch(proc)
        finally:
            if proc.poll() is None:
                self._kill(proc)
        return self.results

    # -------------------------------------------------------------- watching
    def _events(self, offset: int) -> tuple[list[dict], int]:
        with open(self.progress_path, "rb") as f:
            f.seek(offset)
            data = f.read()
        end = data.rfind(b"\n") + 1
        events = [json.loads(line) for line in data[:end].splitlines() if line.strip()]
        return events, offset + end

    def _watch(self, proc: subprocess.Popen) -> None:
        offset = 0
        spawned = time.monotonic()
        while True:
            exited = proc.poll() is not None
            events, offset = self._events(offset)
            for ev in events:
                if self._handle(ev):
                    return
            if exited:
                self._died(proc)
                return
            now = time.monotonic()
            if not self.ready and now - spawned > self.startup_timeout_s:
                self._kill(proc)
                raise GeneratorError(f"the reward probe did not build the env of {self.task_dir} within "
                                     f"{self.startup_timeout_s:g} s; log tail:\n{self._log_tail()}")
            if self.current is not None and now - self.started_at > self.timeout_s:
                self._timed_out(proc)
                return
            if self.current is not None and self.memory_limit_mb:
                rss = _rss_kb(proc.pid)
                if rss - self.baseline_rss_kb > self.memory_limit_mb * 1024:
                    self._over_memory(proc, rss)
                    return
            time.sleep(_POLL_S)

    def _handle(self, ev: dict) -> bool:
        """Apply one progress event; True when the child is finished."""
        kind = ev.get("ev")
        if kind == "ready":
            self.ready = True
            self.baseline_rss_kb = int(ev.get("rss_kb", 0))
        elif kind == "module":
            self.current = int(ev["i"])
            self.started_at = time.monotonic()
            self.last_call = (None, None)
        elif kind == "call":
            self.last_call = (ev.get("fn"), ev.get("step"))
        elif kind == "result":
            i = int(ev["i"])
            self.results[i] = ProbeReport(**ev["report"]) if ev["ok"] else self._error(i, ev["error"])
            self.current = None
        elif kind == "setup_error":
            raise _setup_error(self.task_dir, ev)
        elif kind == "done":
            return True
        return False

    def _error(self, i: int, record: dict) -> RewardCodeError:
        text = f"{self.displays[i]}: {record['message']}"
        if record.get("kind") == "env":
            return RewardProbeError(text + "\n(the env itself failed; if the reward code is not involved this is a "
                                    "simulator problem)")
        return RewardProbeError(text)

    def _where(self) -> tuple[str, str]:
        """(what was running, when) for the current module, from the last ``call`` event."""
        fn, step = self.last_call
        return (fn, _when(step)) if fn else ("importing the module", "")

    def _timed_out(self, proc: subprocess.Popen) -> None:
        i = self.current
        before = self.log_path.stat().st_size
        try:
            os.kill(proc.pid, signal.SIGUSR1)  # faulthandler dumps every thread's stack to the log
        except ProcessLookupError:
            pass
        deadline = time.monotonic() + _STACK_WAIT_S
        where = ""
        while time.monotonic() < deadline and not where:
            time.sleep(_POLL_S)
            where = _stack_location(self._log_text(before), self.modules[i])
        self._kill(proc)
        what, when = self._where()
        self.results[i] = RewardProbeError(
            f"{self.displays[i]}: {what} did not finish within the time limit of {self.timeout_s:g} s "
            f"{when + ' ' if when else ''}(infinite loop?); it was stopped{where}. Reward functions must return "
            "quickly: batched tensor code, no unbounded loops")

    def _over_memory(self, proc: subprocess.Popen, rss_kb: int) -> None:
        i = self.current
        self._kill(proc)
        what, when = self._where()
        self.results[i] = RewardProbeError(
            f"{self.displays[i]}: {what} grew the probe process by {(rss_kb - self.baseline_rss_kb) // 1024} MB "
            f"{when + ', ' if when else ''}over the {self.memory_limit_mb} MB limit; it was stopped. Reward code "
            "must not accumulate data or allocate large tensors")

    def _died(self, proc: subprocess.Popen) -> None:
        if self.current is None and not self.ready:
            raise GeneratorError(f"the reward probe process for {self.task_dir} exited with code {proc.returncode} "
                                 f"before the env was built; log tail:\n{self._log_tail()}")
        if self.current is None:
            if len(self.results) < len(self.modules) and not (
                    self.job["stop_on_error"] and any(isinstance(r, RewardCodeError) for r in self.results.values())):
                raise GeneratorError(f"the reward probe process for {self.task_dir} exited with code "
                                     f"{proc.returncode} between modules; log tail:\n{self._log_tail()}")
            return  # exited after its last result
        i = self.current
        rc = proc.returncode
        how = f"was killed by {signal.Signals(-rc).name}" if rc < 0 else f"exited with code {rc}"
        where = _stack_location(self._log_text(0), self.modules[i])
        what, when = self._where()
        self.results[i] = RewardProbeError(
            f"{self.displays[i]}: the probe process {how} while running {what}{' ' + when if when else ''}{where}; "
            f"log tail:\n{self._log_tail()}")

    # -------------------------------------------------------------- process helpers
    @staticmethod
    def _kill(proc: subprocess.Popen) -> None:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
        proc.wait()

    def _log_text(self, offset: int) -> str:
        with open(self.log_path, "rb") as f:
            f.seek(offset)
            return f.read().decode("utf-8", "replace")

    def _log_tail(self, lines: int = 12) -> str:
        return "\n".join(self._log_text(0).splitlines()[-lines:])


def _probe(task_dir: Path, modules: list[Path], *, steps: int, timeout_s: float, seed: int, num_envs: int,
           sim_backend: str, memory_limit_mb: int | None, startup_timeout_s: float,
           stop_on_error: bool) -> list[ProbeReport | RewardCodeError | None]:
    """Probe ``modules`` in as few processes as possible (a new one only after a module was killed).

    Returns one entry per module: its report, its error, or None when ``stop_on_error`` left it unprobed.
    """
    if not TaskLayout(task_dir).spec.is_file():
        raise TaskNotFoundError(f"{task_dir} holds no task spec ({TaskLayout(task_dir).spec.name})")
    for m in modules:
        if not m.is_file():
            raise FileNotFoundError(f"reward module {m} does not exist")
    displays = [_display(task_dir, m) for m in modules]
    results: list[ProbeReport | RewardCodeError | None] = [None] * len(modules)
    start = 0
    while start < len(modules):
        with tempfile.TemporaryDirectory(prefix="gendex_probe_") as tmp:
            child = _Child(task_dir, modules[start:], displays[start:], steps=steps, timeout_s=timeout_s, seed=seed,
                           num_envs=num_envs, sim_backend=sim_backend, memory_limit_mb=memory_limit_mb,
                           startup_timeout_s=startup_timeout_s, stop_on_error=stop_on_error, workdir=Path(tmp))
            got = child.run()
        for i, r in got.items():
            results[start + i] = r
        if stop_on_error and any(isinstance(r, RewardCodeError) for r in got.values()):
            break
        done = max(got) + 1 if got else len(modules) - start
        start += done
    for m, r in zip(displays, results, strict=True):
        if isinstance(r, ProbeReport):
            log.info("probe %s: ok, reward %.3g..%.3g, success %.2f, %.1f s%s", m, r.reward_min, r.reward_max,
                     r.success_rate, r.wall_s, f", warnings: {r.warnings}" if r.warnings else "")
        elif r is not None:
            log.info("probe %s: rejected: %s", m, r)
    return results


def probe_task(task_dir: str | Path, modules: list[str | Path], *, steps: int = DEFAULT_STEPS,
               timeout_s: float = DEFAULT_TIMEOUT_S, seed: int = 0, num_envs: int = 1,
               sim_backend: str = "physx_cpu", memory_limit_mb: int | None = DEFAULT_MEMORY_LIMIT_MB,
               startup_timeout_s: float = DEFAULT_STARTUP_TIMEOUT_S, check_static: bool = True) -> list[ProbeReport]:
    """Probe several reward modules of one task in one child process; raises for the first bad module.

    Each module gets ``timeout_s`` seconds (import, reset and ``steps`` seeded random-action steps); building the
    env is not charged to it (``startup_timeout_s``). ``check_static`` runs :func:`check_reward_file` on each module
    first (on by default: the probe never executes code that did not pass it unless asked to). Raises
    :class:`~generator.errors.RewardProbeError` (or the static check's error) whose message starts with the
    module's path relative to ``task_dir``.
    """
    task_dir = Path(task_dir)
    paths = [Path(m) for m in modules]
    if check_static:
        for p in paths:
            check_reward_file(p, _display(task_dir, p))
    results = _probe(task_dir, paths, steps=steps, timeout_s=timeout_s, seed=seed, num_envs=num_envs,
                     sim_backend=sim_backend, memory_limit_mb=memory_limit_mb, startup_timeout_s=startup_timeout_s,
                     stop_on_error=True)
    for r in results:
        if isinstance(r, RewardCodeError):
            raise r
    return [r for r in results if isinstance(r, ProbeReport)]


def probe_reward_module(task_dir: str | Path, module_path: str | Path, *, steps: int = DEFAULT_STEPS,
                        timeout_s: float = DEFAULT_TIMEOUT_S, seed: int = 0, **kwargs) -> ProbeReport:
    """:func:`probe_task` for one module."""
    return probe_task(task_dir, [module_path], steps=steps, timeout_s=timeout_s, seed=seed, **kwargs)[0]


def validate_reward_module(task_dir: str | Path, module_path: str | Path, **probe_kwargs) -> ProbeReport:
    """Static check, then the simulator probe, of one module; returns the probe's report or raises."""
    task_dir = Path(task_dir)
    check_reward_file(module_path, _display(task_dir, Path(module_path)))
    return probe_reward_module(task_dir, module_path, check_static=False, **probe_kwargs)


def validate_task(task_dir: str | Path, modules: list[str | Path] | None = None, *, steps: int = DEFAULT_STEPS,
                  timeout_s: float = DEFAULT_TIMEOUT_S, seed: int = 0, num_envs: int = 1,
                  sim_backend: str = "physx_cpu", memory_limit_mb: int | None = DEFAULT_MEMORY_LIMIT_MB,
                  startup_timeout_s: float = DEFAULT_STARTUP_TIMEOUT_S, check_static: bool = True) -> ValidationReport:
    """Validate every module (default: :func:`task_reward_modules`) and report each outcome; does not raise for
    rejected modules (see :meth:`ValidationReport.raise_first`), so the model can get every problem in one round.

    Modules that fail the static check are never run; the others are probed in one child process (a new one is
    started after a module had to be killed). ``check_static=False`` skips the static check (tests of the probe's
    own fences only: never for model output).
    """
    t0 = time.monotonic()
    task_dir = Path(task_dir)
    paths = [Path(m) for m in (task_reward_modules(task_dir) if modules is None else modules)]
    outcomes: dict[int, ModuleOutcome] = {}
    to_probe: list[int] = []
    for i, p in enumerate(paths):
        name = _display(task_dir, p)
        try:
            if check_static:
                check_reward_file(p, name)
        except RewardCodeError as exc:
            outcomes[i] = ModuleOutcome(name, ok=False, failed_at="static", error_type=type(exc).__name__,
                                        error=str(exc))
            log.info("static check %s: rejected: %s", name, exc)
        else:
            to_probe.append(i)
    if to_probe:
        results = _probe(task_dir, [paths[i] for i in to_probe], steps=steps, timeout_s=timeout_s, seed=seed,
                         num_envs=num_envs, sim_backend=sim_backend, memory_limit_mb=memory_limit_mb,
                         startup_timeout_s=startup_timeout_s, stop_on_error=False)
        for i, r in zip(to_probe, results, strict=True):
            name = _display(task_dir, paths[i])
            if isinstance(r, ProbeReport):
                outcomes[i] = ModuleOutcome(name, ok=True, probe=r)
            else:
                outcomes[i] = ModuleOutcome(name, ok=False, failed_at="probe", error_type=type(r).__name__,
                                            error=str(r))
    ordered = [outcomes[i] for i in range(len(paths))]
    return ValidationReport(task_dir=str(task_dir), ok=bool(ordered) and all(o.ok for o in ordered),
                            modules=ordered, steps=steps, seed=seed, wall_s=round(time.monotonic() - t0, 3))
