"""The static check of language-model reward code: parse it and reject anything outside a small, pure-tensor subset
of Python before it ever runs (the rules are in :mod:`generator.steps.reward_rules`).

:func:`check_reward_source` parses the code and rejects anything outside a small, pure-tensor subset of Python
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
"""

from __future__ import annotations

import ast
import builtins
import importlib
import math
import types
from dataclasses import dataclass
from pathlib import Path

from generator.errors import RewardCodeError, UnsafeCodeError
from generator.steps.reward_rules import (
    _FEEDBACK_HINT,
    _FORBIDDEN_ATTR_REASONS,
    ALLOWED_BUILTINS,
    ALLOWED_MODULES,
    ALLOWED_PACKAGES,
    FORBIDDEN_NAMES,
    MAX_LISTED_PROBLEMS,
    MAX_SOURCE_CHARS,
    OPTIONAL_FUNCTIONS,
    REQUIRED_FUNCTIONS,
)


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
