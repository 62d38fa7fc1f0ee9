"""What reward code may use: the allow- and deny-lists of the static check (:mod:`gendex_envs.code_check`).

Reward modules are written by a language model and are untrusted; these lists define the small, pure-tensor subset
of Python they may be written in. Each forbidden attribute carries the reason the feedback to the model states.
"""

from __future__ import annotations

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
    (("scene", "controller", "unwrapped", "px", "physx", "sub_scenes", "teleport", "lock_motion", "gpu_apply",
      "update_render", "build", "remove_from_scene", "data_ptr", "storage", "untyped_storage"),
     "it reaches the simulator, the controller or raw memory; reward code reads only the documented env members"),
):
    for _n in _names:
        _FORBIDDEN_ATTR_REASONS[_n] = _why
FORBIDDEN_ATTRIBUTES = frozenset(_FORBIDDEN_ATTR_REASONS)
"""Attribute names rejected on any object (plus dunders, ``_private`` names and the ``set_*`` prefix)."""

ALLOWED_NODE_TYPES = frozenset({
    # module structure and statements
    "Module", "Expr", "Import", "ImportFrom", "alias", "FunctionDef", "arguments", "arg", "Return", "Assign",
    "AugAssign", "AnnAssign", "For", "While", "If", "With", "withitem", "Raise", "Assert", "Pass", "Break",
    "Continue",
    # expressions
    "BoolOp", "BinOp", "UnaryOp", "Lambda", "IfExp", "Dict", "Set", "ListComp", "SetComp", "DictComp",
    "GeneratorExp", "comprehension", "Compare", "Call", "keyword", "JoinedStr", "FormattedValue", "Constant",
    "Attribute", "Subscript", "Starred", "Name", "List", "Tuple", "Slice",
    # contexts and operators
    "Load", "Store", "Del", "And", "Or", "Add", "Sub", "Mult", "MatMult", "Div", "Mod", "Pow", "LShift", "RShift",
    "BitOr", "BitXor", "BitAnd", "FloorDiv", "Invert", "Not", "UAdd", "USub", "Eq", "NotEq", "Lt", "LtE", "Gt",
    "GtE", "Is", "IsNot", "In", "NotIn",
})
"""Every ``ast`` node class reward code may contain, by name; any other node (``Match`` and its patterns,
``ClassDef``, ``Global``, ``Try``, ``NamedExpr``, ``Delete``, async, ``yield``, ``TypeAlias``...) is rejected."""

REJECTED_NODE_REASONS = {
    "ClassDef": "reward code defines plain functions only",
    "AsyncFunctionDef": "async code is not allowed in reward modules",
    "AsyncFor": "async code is not allowed in reward modules",
    "AsyncWith": "async code is not allowed in reward modules",
    "Await": "async code is not allowed in reward modules",
    "Yield": "reward functions must return their result, not yield",
    "YieldFrom": "reward functions must return their result, not yield",
    "Global": "global/nonlocal statements are not allowed; reward functions keep no state between calls",
    "Nonlocal": "global/nonlocal statements are not allowed; reward functions keep no state between calls",
    "Match": "`match` statements are not allowed (their class patterns read attributes unseen)",
    "NamedExpr": "assignment expressions (`:=`) are not allowed; assign on a line of its own",
    "Try": "try/except is not allowed: errors must surface, not be swallowed",
    "TryStar": "try/except is not allowed: errors must surface, not be swallowed",
    "ExceptHandler": "try/except is not allowed: errors must surface, not be swallowed",
    "Delete": "`del` is not needed in reward code",
}
"""Why common node types outside :data:`ALLOWED_NODE_TYPES` are rejected (others get a generic reason)."""

FRESH_TORCH_FUNCTIONS = frozenset({
    "zeros", "ones", "full", "empty", "zeros_like", "ones_like", "full_like", "empty_like", "rand", "randn",
    "rand_like", "randn_like", "arange", "linspace", "eye", "tensor", "stack", "cat", "where", "clone",
})
"""``torch.<f>(...)`` always returns a new tensor: a local bound to it may be written by subscript."""
FRESH_METHODS = frozenset({
    "clone", "to", "float", "double", "half", "int", "long", "bool", "contiguous", "view", "view_as", "reshape",
    "expand", "expand_as", "unsqueeze", "squeeze", "flatten", "transpose", "permute", "t", "detach", "repeat",
})
"""``x.<m>(...)`` is new (``clone``) or shares memory only with ``x``: fresh when ``x`` is."""
FRESH_BUILTINS = frozenset({"list", "dict", "set", "tuple", "sorted", "len", "float", "int", "bool", "range",
                            "enumerate", "zip", "abs", "round"})
CONTAINER_MUTATORS = frozenset({
    "append", "extend", "insert", "remove", "pop", "popitem", "clear", "update", "setdefault", "discard", "add",
    "sort", "reverse", "difference_update", "intersection_update", "symmetric_difference_update",
})
"""Methods that change their object: allowed only on a list/dict/tensor created in the same function."""
FORBIDDEN_KEYWORDS = {
    "out": "`out=` writes the result into an existing tensor (maybe one the env owns); use the return value",
    "inplace": "`inplace=` changes its input tensor; use the out-of-place result",
}
MAX_POWER_EXPONENT = 64
"""``a ** b`` with a literal exponent above this (or a power of a power of literals) is rejected: ``10**10**10``."""
MAX_INT_LITERAL = 10 ** 12
MAX_REPEAT = 10_000
"""``"x" * n`` / ``[0] * n`` with a literal ``n`` above this is rejected."""

MAX_SOURCE_CHARS = 100_000
"""Longer sources are rejected unparsed (reward modules are a few dozen lines)."""
MAX_SOURCE_BYTES = 4 * MAX_SOURCE_CHARS + 3
"""A reward module file is never read past this many bytes (the most :data:`MAX_SOURCE_CHARS` characters of UTF-8
take, plus a byte-order mark)."""
MAX_LISTED_PROBLEMS = 20

_FEEDBACK_HINT = ("reward code is pure tensor arithmetic on env state: import only torch, math and "
                  "gendex_envs.reward_terms, read env members, return tensors")
