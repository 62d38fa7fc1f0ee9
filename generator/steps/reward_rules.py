"""What reward code may use: the allow- and deny-lists of the static check (:mod:`generator.steps.static_check`).

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
