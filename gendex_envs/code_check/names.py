"""Name, scope, attribute, import, call and store rules of the static check (a mixin of
:class:`gendex_envs.code_check.checker._Checker`): per-scope name resolution with :mod:`symtable`, module attribute
chains resolved against the real modules, and writes only into what the function created."""

from __future__ import annotations

import ast
import builtins
import importlib
import inspect
import symtable
import types

from gendex_envs.code_check.helpers import (
    _FUNCTION_NODES,
    _OP_SYMBOLS,
    _SCOPE_NODES,
    _SYMTABLE_NAMES,
    _allowed_modules_text,
    _attribute_problem,
    _follow,
    _is_dunder,
    _nearest,
    _snippet,
)
from gendex_envs.code_check.rules import (
    _FEEDBACK_HINT,
    ALLOWED_BUILTINS,
    ALLOWED_MODULES,
    ALLOWED_PACKAGES,
    BUILTIN_REASONS,
    CONTAINER_MUTATORS,
    FORBIDDEN_NAMES,
    FRESH_BUILTINS,
    FRESH_METHODS,
    FRESH_TORCH_FUNCTIONS,
    MODULE_MEMBERS,
    VALUE_ATTRIBUTES,
)


class NameRules:
    """Rules about what a name, an attribute, an import, a call or a store may reach (needs ``_Checker``'s state)."""

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
                if name in BUILTIN_REASONS:
                    self.add(use, f"the builtin `{name}` is not allowed in reward code{where}: "
                             f"{BUILTIN_REASONS[name]}")
                elif hasattr(builtins, name):
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
            if not self.check_member(stmt, mod, a.name, f"from {mod} import {a.name}"):
                continue
            obj = self.resolve_chain(stmt, mod, [a.name])
            if isinstance(obj, types.ModuleType):  # e.g. `from gendex_envs.reward_terms import torch`
                self.module_aliases[a.asname or a.name] = obj.__name__
            elif obj is not None:
                self.imported[a.asname or a.name] = obj

    # -------------------------------------------------------------- every node
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
        root, names = self.attr_chain(node)
        if root is None:  # an attribute of a value (a tensor, a view, a dict...), not of a module
            base = node.value
            while isinstance(base, ast.Attribute):
                base = base.value
            undefined = isinstance(base, ast.Name) and base.id not in self.bound_anywhere and not hasattr(
                builtins, base.id)  # reported as undefined already; it would never run
            if not undefined:
                self.check_value_attribute(node, node.attr, f"`{_snippet(self.source, node)}`")
            return
        if isinstance(self.parent.get(node), ast.Attribute):
            return  # the outermost attribute of a chain resolves the whole chain
        if root is not None and not any(_attribute_problem(n) for n in names):
            obj = self.resolve_chain(node, self.module_aliases[root], names, shown=root)
            if isinstance(obj, types.ModuleType):  # `t = F.torch` would alias a module into a variable
                path = ".".join([root, *names])
                self.add(node, f"the module `{path}` may only be used as `{path}.<name>` (line {node.lineno}: "
                         f"`{_snippet(self.source, self.parent.get(node, node))}`), not passed around or stored")

    def check_member(self, node: ast.AST, module: str, name: str, shown: str) -> bool:
        """``module.name`` is on the allow-list (:data:`~gendex_envs.code_check.rules.MODULE_MEMBERS`); else a
        problem naming the nearest allowed names."""
        allowed = MODULE_MEMBERS.get(module)
        if allowed is None or name in allowed:
            return True
        what = f"`{shown}`" if shown.startswith("from ") else f"`{shown}.{name}`"
        self.add(node, f"{what} is not allowed: reward code may use only the pure tensor and math functions on the "
                 f"allow-list from `{module}`, nothing that reads or writes files, exposes memory or changes global "
                 f"state; nearest allowed in `{module}`: {_nearest(name, allowed)}")
        return False

    def check_value_attribute(self, node: ast.AST, name: str, shown: str) -> bool:
        """Attribute ``name`` of a value (not a module) is on the allow-list
        (:data:`~gendex_envs.code_check.rules.VALUE_ATTRIBUTES`: tensor methods, the env view's members, fields of
        results, reading methods of containers); else a problem naming the nearest allowed names."""
        if name in VALUE_ATTRIBUTES:
            return True
        self.add(node, f"attribute `.{name}` in {shown} is not allowed: reward code may use only the allow-listed "
                 "tensor methods (computations that return new tensors), the env view's members and reading methods "
                 f"of its own dicts and lists; nearest allowed: {_nearest(name, VALUE_ATTRIBUTES)}")
        return False

    def resolve_chain(self, node: ast.AST, module: str, names: list[str], shown: str | None = None) -> object:
        """Follow ``module.names...`` in the real (trusted) modules; reject other modules and unknown attributes.

        Returns the object reached, or None when the chain was rejected or could not be followed.
        """
        shown = shown or module
        try:
            obj = importlib.import_module(module)
        except ImportError:  # pragma: no cover - allowed modules are installed
            return None
        path, refused = shown, False
        for n in names:
            if not isinstance(obj, types.ModuleType) and not self.check_value_attribute(node, n, f"`{path}.{n}`"):
                return None
            parent, path = path, f"{path}.{n}"
            try:
                nxt = getattr(obj, n)
            except AttributeError:
                if isinstance(obj, types.ModuleType):
                    allowed = MODULE_MEMBERS.get(obj.__name__, frozenset())
                    self.add(node, f"`{path}` does not exist (module `{obj.__name__}` has no attribute `{n}`); "
                             f"nearest allowed: {_nearest(n, allowed)}", unsafe=False)
                return None
            except Exception:
                return None
            if isinstance(nxt, types.ModuleType) and nxt.__name__ not in ALLOWED_MODULES:
                self.add(node, f"`{path}` is the module `{nxt.__name__}`, which reward code may not use; allowed "
                         f"modules: {_allowed_modules_text()}")
                return None
            if isinstance(obj, types.ModuleType) and not self.check_member(node, obj.__name__, n, parent):
                refused = True  # walk on: a module further along the chain is named as well
            obj = nxt
        return None if refused else obj

    def check_call(self, node: ast.Call) -> None:
        func = node.func
        self.check_positional_inplace(node)
        if self.calls_tensor_type(func):
            self.add(node, f"`{_snippet(self.source, node)}`: calling torch.Tensor is not allowed (with sizes it "
                     "hands out uninitialised memory, like torch.empty); use torch.zeros, torch.full or torch.tensor")
            return
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
        else:
            self.check_value_attribute(node, name, f"`{_snippet(self.source, node)}`")

    def calls_tensor_type(self, func: ast.AST) -> bool:
        """Whether ``func`` names ``torch.Tensor`` (or a subclass of it) through a module alias."""
        import importlib

        import torch

        names: list[str] = []
        while isinstance(func, ast.Attribute):
            names.insert(0, func.attr)
            func = func.value
        if not (isinstance(func, ast.Name) and func.id in self.module_aliases) or not names:
            return False
        try:
            obj = importlib.import_module(self.module_aliases[func.id])
            for name in names:
                obj = getattr(obj, name)
        except (ImportError, AttributeError):
            return False
        return isinstance(obj, type) and issubclass(obj, torch.Tensor)

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
