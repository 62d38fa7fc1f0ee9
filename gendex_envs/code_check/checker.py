"""The static check of language-model reward code: parse it and reject anything outside a small, pure-tensor subset
of Python before it ever runs (the rules are in :mod:`gendex_envs.code_check.rules`).

:func:`check_reward_source` raises :class:`~gendex_envs.errors.UnsafeCodeError` for unsafe constructs, and its base
class :class:`~gendex_envs.errors.RewardCodeError` for syntax, undefined-name and interface problems; the message
lists every problem with its line and what is allowed instead, so it can be fed back to the model. The check is a
fence in front of the runtime guards (a read-only env view, the audit hook): it rejects by construction, not by
listing tricks.

* **Deny what is not known.** Every node of the tree (patterns, decorators, defaults, annotations, f-strings and
  comprehensions included) must be of a class in :data:`~gendex_envs.code_check.rules.ALLOWED_NODE_TYPES`; any other
  node -- ``match`` and all its patterns, ``class``, ``global``/``nonlocal``, ``try``, ``del``, ``:=``, ``async``,
  ``await``, ``yield``, and anything a later Python adds -- is rejected with its node name.
* **No dunder anywhere**: no identifier starting with ``__`` (name, attribute, parameter, keyword, import alias,
  pattern keyword), and no string or bytes literal containing ``__`` (so ``getattr(x, "__class__")``,
  ``"{0.__class__}"`` and ``f"{x:__class__}"`` fail before any lookup). ``str.format``/``format_map`` are rejected
  as attributes; ``getattr``/``hasattr`` take only a literal name, checked like ``obj.name``.
* **Per-scope names** (:mod:`symtable`): a name is judged in the scope that loads it. A builtin outside
  :data:`~gendex_envs.code_check.rules.ALLOWED_BUILTINS` is rejected wherever it is loaded unless that scope, an
  enclosing function or the module binds it, so rebinding ``type`` in one function unlocks nothing elsewhere.
  :data:`~gendex_envs.code_check.rules.FORBIDDEN_NAMES` (``open``, ``exec``, ``eval``, ``compile``, ``globals``,
  ``vars``, ``__import__``, ``breakpoint``, ``print``...) may not appear at all, not even as local names.
* **Imports**: only ``torch`` (and ``torch.nn``, ``torch.nn.functional``, ``torch.linalg``, ``torch.special``,
  ``torch.fft``), ``math`` and ``gendex_envs.reward_terms``, at the top of the module. Attribute chains on modules
  are followed in the real modules, so ``torch.os``, ``torch.load``, ``torch.hub``, ``torch.jit``, ``torch.ops``,
  ``torch.classes``, ``torch.utils`` or ``rt.torch.random`` are rejected wherever they appear; a module may only be
  used as ``module.<name>``. ``numpy`` is not allowed (file I/O, ctypes, GPU->host copies).
* **Attributes: an allow-list** (:mod:`gendex_envs.code_check.rules`, shared with the runtime guard's module
  copies): a name on a module must be in :data:`~gendex_envs.code_check.rules.MODULE_MEMBERS` (torch's pure
  tensor functions, ``math``'s pure functions, ``reward_terms``), a name on any other value in
  :data:`~gendex_envs.code_check.rules.VALUE_ATTRIBUTES` (tensor methods that compute, the env view's members,
  fields of results, reading methods of containers); a rejection names the nearest allowed names. The deny rules
  stay in front for their clearer messages: no ``_private`` names, no setters (``set_*``), no in-place methods
  (any public name ending in ``_``: ``add_``, ``copy_``, ``fill_``, ``zero_``, ``index_put_``, ``scatter_``,
  ``resize_``, ``requires_grad_``, ``share_memory_``...), no simulator handles or mutators (``scene``,
  ``controller``, ``unwrapped``, ``step``, ``reset``, ``apply_*``, ``add_*``...), no file/process/module names, no
  frame introspection (:data:`~gendex_envs.code_check.rules.FORBIDDEN_ATTRIBUTES`).
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
* **Resources**: sources over :data:`~gendex_envs.code_check.rules.MAX_SOURCE_CHARS` are rejected unparsed;
  ``while True`` needs a ``break``/``return``/``raise``; literal powers of powers, exponents or shifts above
  :data:`~gendex_envs.code_check.rules.MAX_POWER_EXPONENT`, huge integer literals and huge sequence repeats are
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
import math
from pathlib import Path

from gendex_envs.code_check.helpers import (
    _ALLOWED_NODES,
    _FUNCTION_NODES,
    _identifiers,
    _literal_number,
    _Problem,
    _snippet,
)
from gendex_envs.code_check.names import NameRules
from gendex_envs.code_check.rules import (
    _FEEDBACK_HINT,
    ALLOWED_NODE_TYPES,
    FORBIDDEN_KEYWORDS,
    FORBIDDEN_NAMES,
    MAX_INT_LITERAL,
    MAX_LISTED_PROBLEMS,
    MAX_POWER_EXPONENT,
    MAX_REPEAT,
    MAX_SOURCE_CHARS,
    OPTIONAL_FUNCTIONS,
    REJECTED_NODE_REASONS,
    REQUIRED_FUNCTIONS,
)
from gendex_envs.code_check.source import read_reward_source
from gendex_envs.errors import RewardCodeError, UnsafeCodeError


class _Checker(NameRules):
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


def check_reward_source(source: str, filename: str = "<reward module>") -> None:
    """Statically check reward module ``source``; returns None when it may be run.

    Raises :class:`~gendex_envs.errors.UnsafeCodeError` when any unsafe construct is present, else
    :class:`~gendex_envs.errors.RewardCodeError` for syntax errors, undefined names and interface problems. The
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


def check_reward_file(path: str | Path, filename: str | None = None) -> str:
    """:func:`check_reward_source` on a file (``filename`` defaults to the file's name), read once and strictly as
    UTF-8 by :func:`~gendex_envs.code_check.source.read_reward_source`; returns the text that was checked, which
    is the text to run."""
    path = Path(path)
    source = read_reward_source(path, filename or path.name)
    check_reward_source(source, filename or path.name)
    return source
