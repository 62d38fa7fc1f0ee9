"""The static check of language-model reward code: parse it and reject anything outside a small, pure-tensor subset
of Python before it ever runs (the rules are in :mod:`generator.steps.reward_rules`).

:func:`check_reward_source` raises :class:`~generator.errors.UnsafeCodeError` for unsafe constructs, and its base
class :class:`~generator.errors.RewardCodeError` for syntax, undefined-name and interface problems; the message
lists every problem with its line and what is allowed instead, so it can be fed back to the model. The check is a
fence in front of the runtime guards (a read-only env view, the audit hook): it rejects by construction, not by
listing tricks.

* **Deny what is not known.** Every node of the tree (patterns, decorators, defaults, annotations, f-strings and
  comprehensions included) must be of a class in :data:`~generator.steps.reward_rules.ALLOWED_NODE_TYPES`; any other
  node -- ``match`` and all its patterns, ``class``, ``global``/``nonlocal``, ``try``, ``del``, ``:=``, ``async``,
  ``await``, ``yield``, and anything a later Python adds -- is rejected with its node name.
* **No dunder anywhere**: no identifier starting with ``__`` (name, attribute, parameter, keyword, import alias,
  pattern keyword), and no string or bytes literal containing ``__`` (so ``getattr(x, "__class__")``,
  ``"{0.__class__}"`` and ``f"{x:__class__}"`` fail before any lookup). ``str.format``/``format_map`` are rejected
  as attributes; ``getattr``/``hasattr`` take only a literal name, checked like ``obj.name``.
* **Per-scope names** (:mod:`symtable`): a name is judged in the scope that loads it. A builtin outside
  :data:`~generator.steps.reward_rules.ALLOWED_BUILTINS` is rejected wherever it is loaded unless that scope, an
  enclosing function or the module binds it, so rebinding ``type`` in one function unlocks nothing elsewhere.
  :data:`~generator.steps.reward_rules.FORBIDDEN_NAMES` (``open``, ``exec``, ``eval``, ``compile``, ``globals``,
  ``vars``, ``__import__``, ``breakpoint``, ``print``...) may not appear at all, not even as local names.
* **Imports**: only ``torch`` (and ``torch.nn``, ``torch.nn.functional``, ``torch.linalg``, ``torch.special``,
  ``torch.fft``), ``math`` and ``gendex_envs.reward_terms``, at the top of the module. Attribute chains on modules
  are followed in the real modules, so ``torch.os``, ``torch.load``, ``torch.hub``, ``torch.jit``, ``torch.ops``,
  ``torch.classes``, ``torch.utils`` or ``rt.torch.random`` are rejected wherever they appear; a module may only be
  used as ``module.<name>``. ``numpy`` is not allowed (file I/O, ctypes, GPU->host copies).
* **Attributes**: no ``_private`` names, no setters (``set_*``), no in-place methods (any public name ending in
  ``_``: ``add_``, ``copy_``, ``fill_``, ``zero_``, ``index_put_``, ``scatter_``, ``resize_``, ``requires_grad_``,
  ``share_memory_``...), no simulator handles or mutators (``scene``, ``controller``, ``unwrapped``, ``step``,
  ``reset``, ``apply_*``, ``add_*``...), no file/process/module names, no frame introspection
  (:data:`~generator.steps.reward_rules.FORBIDDEN_ATTRIBUTES`).
* **No mutation of anything the function did not create.** Attribute stores are rejected; a subscript store
  ``x[i] = v`` is allowed only when every binding of the local ``x`` in that function is a new object
  (``torch.zeros_like(...)``, arithmetic, a literal list/dict, ``.clone()``...), never a parameter, a loop variable
  or a tensor the env returned; ``x += v`` (in place on tensors) likewise; ``x[i] += v`` never; container mutators
  (``append``, ``update``, ``pop``, ``clear``...) only on such fresh locals (so ``info["success"] = ...`` and
  ``info.update(...)`` fail); ``out=``, ``inplace=``, ``inplace`` passed positionally and ``**`` unpacking in calls
  are rejected.
* **No state across calls** (misbehaviour deferred past the probe's window needs it): the top level holds only a
  docstring, imports, functions and constant assignments (numbers, strings, tuples, arithmetic); defaults are
  literal constants; no ``global``/``nonlocal``, no attribute stores on functions or modules.
* **Resources**: sources over :data:`~generator.steps.reward_rules.MAX_SOURCE_CHARS` are rejected unparsed;
  ``while True`` needs a ``break``/``return``/``raise``; literal powers of powers, exponents or shifts above
  :data:`~generator.steps.reward_rules.MAX_POWER_EXPONENT`, huge integer literals and huge sequence repeats are
  rejected; the walk is iterative, and too-deep nesting gives an ``UnsafeCodeError``, never a crash. Any
  unexpected failure of the checker itself is reported as ``UnsafeCodeError`` (fail closed).
* **Interface**: ``evaluate(env)`` and ``compute_dense_reward(env, obs, action, info)`` are required,
  ``_get_obs_extra(env, info)`` is optional, with exactly those parameter counts; ``REWARD_MAX`` if literal must
  be > 0.

Why not RestrictedPython: it is maintained and built for untrusted code, but (its own documentation says) it "is
not a sandbox system": it rewrites the AST so that attribute reads, item reads, writes and iteration call guard
hooks (``_getattr_``, ``_write_``, ``_getitem_``...) that the embedding application must implement and inject into
the globals at ``exec`` time. Using it would mean executing reward modules through ``compile_restricted`` with
custom globals instead of importing them (the env loads them as ordinary modules), writing the policy ourselves
anyway, and paying a guard call on every attribute access in the per-step reward path. Its write guard sees
``x.attr = v`` and ``x[i] = v`` but not ``t.add_(1)``, ``torch.add(a, b, out=t)`` or ``t += 1`` on a tensor -- the
mutations that matter here happen inside torch's C++ code. Its default policy is also shaped for a different use
(Zope scripts): it allows ``class``, ``try`` and iteration over arbitrary objects and leaves writes to the
application's ``_write_`` guard, while it forbids every name starting with ``_``, which our interface
(``_get_obs_extra``) and the committed modules' helpers (``_pregrasp``) need. Our
subset is tiny, fixed, and allow-listed node by node, so a static check with no runtime hooks covers it, and the
runtime side is fenced separately (read-only env view, audit hook). We borrow its ideas (an allow-listed grammar,
no underscore attributes, a guarded ``getattr``), not its code.
"""

from __future__ import annotations

import ast
import builtins
import importlib
import inspect
import math
import symtable
import types
from dataclasses import dataclass
from pathlib import Path

from generator.errors import RewardCodeError, UnsafeCodeError
from generator.steps.reward_rules import (
    _FEEDBACK_HINT,
    _FORBIDDEN_ATTR_REASONS,
    ALLOWED_BUILTINS,
    ALLOWED_MODULES,
    ALLOWED_NODE_TYPES,
    ALLOWED_PACKAGES,
    CONTAINER_MUTATORS,
    FORBIDDEN_KEYWORDS,
    FORBIDDEN_NAMES,
    FRESH_BUILTINS,
    FRESH_METHODS,
    FRESH_TORCH_FUNCTIONS,
    MAX_INT_LITERAL,
    MAX_LISTED_PROBLEMS,
    MAX_POWER_EXPONENT,
    MAX_REPEAT,
    MAX_SOURCE_CHARS,
    OPTIONAL_FUNCTIONS,
    REJECTED_NODE_REASONS,
    REQUIRED_FUNCTIONS,
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


class _Checker:
    """One pass over a parsed module; collects every problem (iterative: deep expressions cannot overflow)."""

    def __init__(self, source: str, tree: ast.Module):
        self.source = source
        self.tree = tree
        self.problems: list[_Problem] = []
        self.parent: dict[ast.AST, ast.AST] = {}
        self.scope: dict[ast.AST, ast.AST] = {tree: tree}
        """Node -> the scope node (module, function, lambda, comprehension) it is evaluated in."""
        self.nodes: list[ast.AST] = [tree]
        stack: list[ast.AST] = [tree]
        while stack:
            node = stack.pop()
            for child in ast.iter_child_nodes(node):
                self.parent[child] = node
                self.scope[child] = self._child_scope(node, child)
                self.nodes.append(child)
                stack.append(child)
        self.nodes.sort(key=lambda n: (getattr(n, "lineno", 0), getattr(n, "col_offset", 0)))
        self.module_aliases: dict[str, str] = {}
        """Name bound by an import -> the dotted module it names (only for names that are modules)."""
        self.imported: dict[str, object] = {}
        """Name bound by ``from <allowed module> import <name>`` -> the (trusted) object it names."""
        self.module_bound: set[str] = set()
        """Names the module's top level binds (imports, functions, constants)."""
        self.bound_anywhere: set[str] = set()
        """Every name bound anywhere (a builtin such as ``list`` counts as fresh-making only when never rebound)."""
        self.bindings: dict[ast.AST, dict[str, list[ast.AST | None]]] = {}
        """Function scope -> name -> the values bound to it there (None: bound by a parameter, a loop...)."""

    def _child_scope(self, node: ast.AST, child: ast.AST) -> ast.AST:
        """The scope ``child`` of ``node`` is evaluated in (Python's rules: defaults, decorators, annotations and a
        comprehension's first iterable belong to the enclosing scope; parameters are found through their function)."""
        outer = self.scope[node]
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            return node if child in node.body else outer
        if isinstance(node, ast.Lambda):
            return node if child is node.body else outer
        if isinstance(node, ast.ListComp | ast.SetComp | ast.DictComp | ast.GeneratorExp):
            return node
        if isinstance(node, ast.comprehension):
            comp = self.parent.get(node)
            generators = getattr(comp, "generators", None) or [None]
            if generators[0] is node and child is node.iter:  # the first iterable is evaluated outside
                return self.scope[comp]
            return outer
        if isinstance(node, ast.ClassDef):
            return outer if child not in node.body else node
        return outer

    # -------------------------------------------------------------- helpers
    def add(self, node: ast.AST, message: str, unsafe: bool = True) -> None:
        self.problems.append(_Problem(getattr(node, "lineno", 0), message, unsafe))

    def function_of(self, node: ast.AST) -> ast.AST | None:
        """The innermost function or lambda whose body holds ``node`` (comprehensions see through), or None."""
        cur = self.scope.get(node)
        while cur is not None and not isinstance(cur, _FUNCTION_NODES):
            if isinstance(cur, ast.Module):
                return None
            cur = self.scope.get(cur)
        return cur

    # -------------------------------------------------------------- entry
    def run(self) -> list[_Problem]:
        self.check_node_types()
        self.check_top_level()
        self.check_scopes()
        self.collect_bindings()
        for node in self.nodes:
            self.check_node(node)
        self.check_interface()
        return self.problems

    def check_node_types(self) -> None:
        """Deny what is not known: every node must be of an allowed class; identifiers and strings hold no dunder."""
        for node in self.nodes:
            name = type(node).__name__
            if not isinstance(node, _ALLOWED_NODES) or name not in ALLOWED_NODE_TYPES:
                parent = self.parent.get(node)
                if parent is None or isinstance(parent, _ALLOWED_NODES):  # report the outermost node only
                    reason = REJECTED_NODE_REASONS.get(name, "it is outside the small subset of Python reward code "
                                                             "may use")
                    self.add(node, f"{self.describe(node)} is not allowed in reward code ({name}): {reason}")
            for ident in _identifiers(node):
                if ident.startswith("__") and not (isinstance(node, ast.ImportFrom) and ident == "__future__"):
                    self.add(node, f"`{ident}` is not allowed in reward code: no dunder or mangled name may appear "
                             f"anywhere ({_FEEDBACK_HINT})")
            if isinstance(node, ast.Constant) and isinstance(node.value, str | bytes):
                text = node.value if isinstance(node.value, str) else node.value.decode("latin-1")
                if "__" in text:
                    self.add(node, f"the string {_snippet(self.source, node, 40) or repr(text[:30])} contains `__`: "
                             "dunder names may not appear in reward code, not even in strings")
            if isinstance(node, ast.BinOp):
                self.check_big_constant(node)
            elif isinstance(node, ast.Constant) and isinstance(node.value, int) and not isinstance(node.value, bool):
                if abs(node.value) > MAX_INT_LITERAL:
                    self.add(node, f"the integer literal {_snippet(self.source, node, 30)} is too large (limit "
                             f"{MAX_INT_LITERAL:.0e}); use a float")

    def describe(self, node: ast.AST) -> str:
        if isinstance(node, ast.ClassDef):
            return f"class `{node.name}`"
        if isinstance(node, ast.AsyncFunctionDef):
            return f"async function `{node.name}`"
        return f"`{_snippet(self.source, node, 50)}`"

    def check_big_constant(self, node: ast.BinOp) -> None:
        """``10**10**10``, ``2 << 10**6``, ``"x" * 10**9``: literal arithmetic that would hang or eat the memory."""
        def literal(n: ast.AST) -> bool:
            return isinstance(n, ast.Constant) or (isinstance(n, ast.UnaryOp) and isinstance(n.operand, ast.Constant))

        def value(n: ast.AST) -> float | None:
            v = _literal_number(n) if literal(n) else None
            return v

        if isinstance(node.op, ast.Pow | ast.LShift):
            exp = value(node.right)
            if isinstance(node.right, ast.BinOp) and isinstance(node.right.op, ast.Pow | ast.LShift):
                self.add(node, f"`{_snippet(self.source, node)}`: a power of a power is not allowed (huge numbers "
                         "take forever to compute)")
            elif exp is not None and abs(exp) > MAX_POWER_EXPONENT:
                self.add(node, f"`{_snippet(self.source, node)}`: the exponent/shift {exp:g} is larger than "
                         f"{MAX_POWER_EXPONENT} (huge numbers take forever to compute)")
        elif isinstance(node.op, ast.Mult):
            for seq, count in ((node.left, node.right), (node.right, node.left)):
                n = value(count)
                if isinstance(seq, ast.List | ast.Tuple) or (isinstance(seq, ast.Constant) and
                                                            isinstance(seq.value, str | bytes)):
                    if n is not None and n > MAX_REPEAT:
                        self.add(node, f"`{_snippet(self.source, node)}` repeats a sequence {n:g} times (limit "
                                 f"{MAX_REPEAT})")

    # -------------------------------------------------------------- scopes
    def check_scopes(self) -> None:
        """Per-scope name resolution with :mod:`symtable`: a name loaded where neither its own scope, an enclosing
        function nor the module binds it is a builtin; only :data:`ALLOWED_BUILTINS` may be used that way."""
        try:
            top = symtable.symtable(self.source, "<reward module>", "exec")
        except SyntaxError as exc:
            self.add(self.tree, f"the module does not compile: {exc.msg} (line {exc.lineno})", unsafe=False)
            return
        module_bound = self.module_bound = {s.get_name() for s in top.get_symbols() if s.is_assigned()
                                            or s.is_imported() or s.is_namespace() or s.is_parameter()}
        tables = [top]
        while tables:
            table = tables.pop()
            tables.extend(table.get_children())
            for sym in table.get_symbols():
                name = sym.get_name()
                if (not sym.is_referenced() or sym.is_local() or sym.is_free() or name in module_bound
                        or name in ALLOWED_BUILTINS or name in FORBIDDEN_NAMES
                        or name.startswith(("__", "."))):
                    continue
                use = self.find_use(table, name)
                where = "" if table.get_type() == "module" else f" (in `{table.get_name()}`)"
                if hasattr(builtins, name):
                    self.add(use, f"the builtin `{name}` is not allowed in reward code{where}; allowed builtins: "
                             f"{', '.join(sorted(ALLOWED_BUILTINS))}")
                else:
                    self.add(use, f"name `{name}` is not defined{where} (line {getattr(use, 'lineno', 0)}: "
                             f"`{_snippet(self.source, self.parent.get(use, use))}`)", unsafe=False)

    def find_use(self, table: symtable.SymbolTable, name: str) -> ast.AST:
        """The first load of ``name`` in the AST scope(s) matching a symbol table (for the line of a message)."""
        if table.get_type() == "module":
            scopes: list[ast.AST] = [self.tree]
        else:
            tname, line = table.get_name(), table.get_lineno()
            scopes = [n for n in self.nodes if isinstance(n, _SCOPE_NODES) and getattr(n, "lineno", -1) == line
                      and (getattr(n, "name", None) == tname or _SYMTABLE_NAMES.get(type(n)) == tname)]
        for node in self.nodes:
            if (isinstance(node, ast.Name) and node.id == name and isinstance(node.ctx, ast.Load)
                    and (self.scope.get(node) in scopes or not scopes)):
                return node
        return scopes[0] if scopes else self.tree

    # -------------------------------------------------------------- freshness (what a function created itself)
    def collect_bindings(self) -> None:
        for node in self.nodes:
            if isinstance(node, ast.Name) and not isinstance(node.ctx, ast.Load):
                self.bound_anywhere.add(node.id)
            elif isinstance(node, ast.arg):
                self.bound_anywhere.add(node.arg)
            elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
                self.bound_anywhere.add(node.name)
                fn = self.function_of(node)
                if fn is not None:
                    self.bindings.setdefault(fn, {}).setdefault(node.name, []).append(None)
            elif isinstance(node, ast.alias):
                self.bound_anywhere.add((node.asname or node.name).split(".")[0])
            if not isinstance(node, ast.Name | ast.arg):
                continue
            if isinstance(node, ast.arg):  # a parameter: bound to whatever the caller passes
                fn = self.parent.get(self.parent.get(node))
                if isinstance(fn, _FUNCTION_NODES):
                    self.bindings.setdefault(fn, {}).setdefault(node.arg, []).append(None)
                continue
            fn = self.function_of(node)
            if fn is None:
                continue
            if not isinstance(node.ctx, ast.Store) or self.scope.get(node) is not fn:
                continue
            self.bindings.setdefault(fn, {}).setdefault(node.id, []).append(self.bound_value(node))

    def bound_value(self, name: ast.Name) -> ast.AST | None:
        """The expression assigned to ``name`` (by ``=``, ``x: T = v`` or tuple unpacking of a literal tuple), the
        target itself for ``+=`` (keeps freshness), or None (a loop target, ``with ... as``, unpacking)."""
        parent = self.parent.get(name)
        if isinstance(parent, ast.AugAssign):
            return parent
        if isinstance(parent, ast.AnnAssign):
            return parent.value
        if isinstance(parent, ast.Assign):
            return parent.value
        if isinstance(parent, ast.Tuple | ast.List) and isinstance(self.parent.get(parent), ast.Assign):
            value = self.parent[parent].value
            if isinstance(value, ast.Tuple | ast.List) and len(value.elts) == len(parent.elts) and not any(
                    isinstance(e, ast.Starred) for e in (*value.elts, *parent.elts)):
                return value.elts[parent.elts.index(name)]
        return None

    def is_fresh_name(self, name: str, fn: ast.AST | None, seen: frozenset[str] = frozenset()) -> bool:
        """True when every binding of local ``name`` in ``fn`` is a value the function created itself."""
        if fn is None or name in seen:
            return False
        values = self.bindings.get(fn, {}).get(name)
        if not values:
            return False
        return all(v is not None and (isinstance(v, ast.AugAssign) or self.is_fresh(v, fn, seen | {name}))
                   for v in values)

    def is_fresh(self, node: ast.AST, fn: ast.AST | None, seen: frozenset[str] = frozenset()) -> bool:
        """Conservatively: ``node`` evaluates to a new object (never a tensor or container the env or a caller
        owns), so writing into it changes nothing outside the function."""
        if isinstance(node, ast.Constant | ast.List | ast.Tuple | ast.Set | ast.Dict | ast.ListComp | ast.SetComp |
                      ast.DictComp | ast.GeneratorExp | ast.BinOp | ast.Compare | ast.JoinedStr):
            return True
        if isinstance(node, ast.UnaryOp):
            return not isinstance(node.op, ast.UAdd)  # `+t` is torch.positive: it returns `t` itself
        if isinstance(node, ast.BoolOp):
            return all(self.is_fresh(v, fn, seen) for v in node.values)
        if isinstance(node, ast.IfExp):
            return self.is_fresh(node.body, fn, seen) and self.is_fresh(node.orelse, fn, seen)
        if isinstance(node, ast.Name):
            return self.is_fresh_name(node.id, fn, seen)
        if isinstance(node, ast.Call):
            func = node.func
            if isinstance(func, ast.Name):
                return func.id in FRESH_BUILTINS and func.id not in self.bound_anywhere
            if isinstance(func, ast.Attribute):
                root, names = self.attr_chain(func)
                if root is not None:
                    return self.module_aliases.get(root) == "torch" and len(names) == 1 and \
                        names[0] in FRESH_TORCH_FUNCTIONS
                if func.attr == "clone":
                    return True
                return func.attr in FRESH_METHODS and self.is_fresh(func.value, fn, seen)
        return False

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
            elif obj is not None:
                self.imported[a.asname or a.name] = obj

    # -------------------------------------------------------------- every node
    def check_node(self, node: ast.AST) -> None:
        src = self.source
        if isinstance(node, ast.Import | ast.ImportFrom) and self.parent.get(node) is not self.tree:
            self.add(node, f"`{_snippet(src, node)}`: imports belong at the top of the module, not inside "
                     "functions or blocks")
        elif isinstance(node, ast.FunctionDef | ast.Lambda):
            self.check_function(node)
        elif isinstance(node, ast.Name):
            self.check_name(node)
        elif isinstance(node, ast.Attribute):
            self.check_attribute(node)
        elif isinstance(node, ast.Call):
            self.check_call(node)
        elif isinstance(node, ast.keyword):
            if node.arg is None:
                self.add(node, f"`**{_snippet(src, node.value)}` in a call is not allowed: pass keyword arguments "
                         "by name (unpacking hides names such as `out=`)")
            elif node.arg in FORBIDDEN_KEYWORDS:
                self.add(node, f"keyword `{node.arg}=` in `{_snippet(src, self.parent.get(node, node))}` is not "
                         f"allowed: {FORBIDDEN_KEYWORDS[node.arg]}")
        elif isinstance(node, ast.Assign | ast.AugAssign | ast.AnnAssign):
            if isinstance(node, ast.AnnAssign):
                self.check_annotation(node.annotation)
            self.check_store(node)
        elif isinstance(node, ast.Subscript | ast.Attribute | ast.Starred) and not isinstance(node.ctx, ast.Load):
            pass  # judged with their statement by check_store
        elif isinstance(node, ast.While):
            self.check_while(node)
        if isinstance(node, ast.Attribute | ast.Subscript) and not isinstance(node.ctx, ast.Load):
            stmt = self.parent.get(node)
            while isinstance(stmt, ast.Tuple | ast.List | ast.Starred):
                stmt = self.parent.get(stmt)
            if not isinstance(stmt, ast.Assign | ast.AugAssign | ast.AnnAssign):  # for-targets, with-as, ...
                self.add(node, f"`{_snippet(src, node)}` writes into an object as a loop or `with` target; reward "
                         "code must not modify the env or other objects (compute into local variables instead)")
        if isinstance(node, ast.arg | ast.FunctionDef):
            name = node.arg if isinstance(node, ast.arg) else node.name
            if name in FORBIDDEN_NAMES:
                self.add(node, f"the name `{name}` may not be used in reward code")
            if name in self.module_aliases:
                self.add(node, f"`{name}` rebinds the imported module `{self.module_aliases[name]}`; pick "
                         "another name")

    def check_store(self, stmt: ast.Assign | ast.AugAssign | ast.AnnAssign) -> None:
        """Writes go only into what the function itself created: attribute stores never, subscript stores only into
        a local bound to a new tensor/list/dict, ``+=`` only on such a local (``t += 1`` changes a tensor in
        place, so on a tensor the env handed out it would change the simulation's state)."""
        src = self.source
        targets = stmt.targets if isinstance(stmt, ast.Assign) else [stmt.target]
        fn = self.function_of(stmt)
        for target in targets:
            for sub in ast.walk(target):
                if isinstance(sub, ast.Attribute) and isinstance(sub.ctx, ast.Store | ast.Del):
                    self.add(stmt, f"`{_snippet(src, stmt)}` changes an attribute; reward code must not modify "
                             "the env or other objects (compute into local variables instead)")
                elif isinstance(sub, ast.Subscript) and isinstance(sub.ctx, ast.Store | ast.Del):
                    base = sub.value
                    if isinstance(stmt, ast.AugAssign):
                        self.add(stmt, f"`{_snippet(src, stmt)}`: augmented assignment into a subscript changes "
                                 "a tensor in place; write `x = x + ...` on a new variable (or `torch.where`)")
                    elif not (isinstance(base, ast.Name) and self.is_fresh_name(base.id, fn)):
                        self.add(stmt, f"`{_snippet(src, stmt)}` writes into `{_snippet(src, base, 40)}`, which "
                                 "this function did not create (it may be a tensor the env returned or an "
                                 "argument); reward code must not modify the env's data: build a new tensor "
                                 "(`torch.where(...)`, or `x = x.clone()` first)")
        if isinstance(stmt, ast.AugAssign) and isinstance(stmt.target, ast.Name):
            if not self.is_fresh_name(stmt.target.id, fn):
                self.add(stmt, f"`{_snippet(src, stmt)}` may change `{stmt.target.id}` in place, and "
                         f"`{stmt.target.id}` is not a value this function created (it may be a tensor the env "
                         f"returned or an argument); write `{stmt.target.id} = {stmt.target.id} "
                         f"{_OP_SYMBOLS.get(type(stmt.op), '+')} ...` instead")

    def check_function(self, node: ast.FunctionDef | ast.Lambda) -> None:
        args = node.args
        if isinstance(node, ast.FunctionDef):
            if node.decorator_list:
                self.add(node.decorator_list[0], f"decorator on `{node.name}` is not allowed: decorators run at "
                         "import time")
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
                         "(defaults are evaluated at import time and kept between calls)")

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
        if not isinstance(node.ctx, ast.Load) and name in self.module_aliases and self.scope.get(node) is not \
                self.tree:
            self.add(node, f"`{name}` rebinds the imported module `{self.module_aliases[name]}`; pick another name")

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
        if node.attr in CONTAINER_MUTATORS:  # called or passed on (`map(info.update, ...)`)
            root, names = self.attr_chain(node)
            module_function = root is not None and len(names) == 1  # `torch.add(...)`, not `rt.CACHE.update()`
            if not module_function and not self.is_fresh(node.value, self.function_of(node)):
                call = self.parent.get(node)
                shown = call if isinstance(call, ast.Call) and call.func is node else node
                self.add(node, f"`{_snippet(self.source, shown)}`: `.{node.attr}()` changes "
                         f"`{_snippet(self.source, node.value, 40)}`, which this function did not create (it may be "
                         "the env's data or an argument such as `info`); build a new list/dict/tensor instead")
        if isinstance(self.parent.get(node), ast.Attribute):
            return  # the outermost attribute of a chain resolves the whole chain
        root, names = self.attr_chain(node)
        if root is not None and not any(_attribute_problem(n) for n in names):
            obj = self.resolve_chain(node, self.module_aliases[root], names, shown=root)
            if isinstance(obj, types.ModuleType):  # `t = F.torch` would alias a module into a variable
                path = ".".join([root, *names])
                self.add(node, f"the module `{path}` may only be used as `{path}.<name>` (line {node.lineno}: "
                         f"`{_snippet(self.source, self.parent.get(node, node))}`), not passed around or stored")

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
        func = node.func
        self.check_positional_inplace(node)
        if not isinstance(func, ast.Name) or func.id not in ("getattr", "hasattr"):
            return
        fn = func.id
        if len(node.args) < 2 or not (isinstance(node.args[1], ast.Constant) and isinstance(node.args[1].value,
                                                                                             str)):
            self.add(node, f"`{_snippet(self.source, node)}`: {fn} needs a literal attribute name, e.g. "
                     f"`{fn}(env, \"goal_pos\")`")
            return
        name = node.args[1].value
        why = _attribute_problem(name) or ("it changes its object; call it as a method on a list/dict this function "
                                           "created" if name in CONTAINER_MUTATORS else None)
        if why:
            self.add(node, f"`{_snippet(self.source, node)}` is not allowed: `{name}`: {why}")
            return
        first = node.args[0]
        if isinstance(first, ast.Name) and first.id in self.module_aliases:
            obj = self.resolve_chain(node, self.module_aliases[first.id], [name], shown=first.id)
            if fn == "getattr" and isinstance(obj, types.ModuleType):
                self.add(node, f"`{_snippet(self.source, node)}` returns the module `{obj.__name__}`; use "
                         f"`{first.id}.{name}.<name>` directly")

    def check_positional_inplace(self, node: ast.Call) -> None:
        """``F.relu(t, True)``, ``F.dropout(t, 0.5, True, True)``, ``torch.nn.ReLU(True)``: a torch callable with an
        ``inplace`` parameter may not receive it positionally (by keyword it is rejected as ``inplace=``)."""
        func, obj = node.func, None
        if isinstance(func, ast.Name) and func.id in self.imported and func.id not in self.bindings.get(
                self.function_of(node), {}):
            obj = self.imported[func.id]
        elif isinstance(func, ast.Attribute):
            root, names = self.attr_chain(func)
            if root is not None and not any(_attribute_problem(n) for n in names):
                obj = _follow(self.module_aliases[root], names)
        if obj is None or not callable(obj):
            return
        try:
            params = list(inspect.signature(obj).parameters.values())
        except (TypeError, ValueError):
            return
        positional = [p.name for p in params if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
        if "inplace" not in positional:
            return
        index = positional.index("inplace")
        if len(node.args) > index or any(isinstance(a, ast.Starred) for a in node.args):
            self.add(node, f"`{_snippet(self.source, node)}` passes `inplace` positionally: the call would change "
                         "its input tensor in place; leave `inplace` at its default")

    def check_while(self, node: ast.While) -> None:
        test = node.test
        constant = not any(isinstance(n, ast.Name | ast.Attribute | ast.Call | ast.Subscript) for n in ast.walk(test))
        if not constant or (isinstance(test, ast.Constant) and not test.value):
            return  # `while 1 == 1`, `while not False`: a condition without variables never changes
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
    except (RecursionError, MemoryError):
        raise UnsafeCodeError(f"{filename}: expressions are nested too deeply to check; simplify the code") from None
    except Exception as exc:  # fail closed: code the checker cannot analyse is never run
        raise UnsafeCodeError(f"{filename}: the static check could not analyse this code ({type(exc).__name__}); "
                              "write plain reward functions") from exc
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
