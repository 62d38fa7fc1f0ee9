"""What reward code may use: the allow-lists shared by the static check (:mod:`gendex_envs.code_check`) and the
runtime guard's module copies (:mod:`gendex_envs.guard`), and the deny rules kept in front of them for their
clearer messages.

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

# ---------------------------------------------------------------------------------------------- the allow-lists
# What reward code may reach, by name: one place, read by the static check (attribute chains on modules, method
# names on values) and by the runtime guard (its module copies hold exactly these names; gendex_envs.guard).
# Everything else is refused: no file, storage, raw-memory, RNG or global-state function of torch is named here.
# Derived from every committed reward module (they use about 20 of these names) plus the pure tensor math a
# model would reasonably write. Deliberately absent, among others: torch.empty*/new_empty (uninitialised memory),
# as_strided* (reads arbitrary memory), frombuffer/asarray/from_numpy/from_dlpack (tensors over interpreter
# buffers), from_file/save/load/get_file_path (files), every *Storage, rand*/normal/bernoulli/multinomial/dropout
# (they advance the global generator the env resets with), Tensor.numpy/storage/untyped_storage/data_ptr/
# pin_memory/share_memory_/tofile, and every in-place `*_` method.

_TORCH_CREATION = (
    "zeros", "ones", "full", "zeros_like", "ones_like", "full_like", "arange", "linspace", "logspace", "eye",
    "tensor", "as_tensor", "scalar_tensor", "complex", "polar", "tril_indices", "triu_indices", "meshgrid",
    "cartesian_prod", "combinations", "diag", "diag_embed", "diagflat", "block_diag", "vander",
)
_TORCH_ELEMENTWISE = (
    "abs", "absolute", "acos", "arccos", "acosh", "arccosh", "asin", "arcsin", "asinh", "arcsinh", "atan",
    "arctan", "atan2", "arctan2", "atanh", "arctanh", "add", "sub", "subtract", "mul", "multiply", "div", "divide",
    "true_divide", "floor_divide", "remainder", "fmod", "pow", "float_power", "sqrt", "rsqrt", "square", "exp",
    "exp2", "expm1", "log", "log2", "log10", "log1p", "logaddexp", "logaddexp2", "sin", "cos", "tan", "sinh", "cosh",
    "tanh", "sinc", "sigmoid", "logit", "erf", "erfc", "erfinv", "lgamma", "digamma", "polygamma", "mvlgamma", "i0",
    "xlogy", "hypot", "neg", "negative", "positive", "reciprocal", "sign", "sgn", "signbit", "copysign", "ceil",
    "floor", "round", "trunc", "fix", "frac", "clamp", "clip", "clamp_min", "clamp_max", "lerp", "deg2rad",
    "rad2deg", "nan_to_num", "heaviside", "nextafter", "ldexp", "frexp", "angle", "real", "imag", "conj",
    "view_as_real", "view_as_complex", "bitwise_and", "bitwise_or", "bitwise_xor", "bitwise_not",
    "bitwise_left_shift", "bitwise_right_shift", "logical_and", "logical_or", "logical_not", "logical_xor", "gcd",
    "lcm", "relu", "softmax", "log_softmax", "addcmul", "addcdiv",
)
_TORCH_COMPARISON = (
    "eq", "ne", "not_equal", "lt", "less", "le", "less_equal", "gt", "greater", "ge", "greater_equal", "maximum",
    "minimum", "fmax", "fmin", "isclose", "allclose", "equal", "isfinite", "isinf", "isnan", "isneginf", "isposinf",
    "isreal", "isin", "is_tensor", "is_floating_point", "is_complex", "is_nonzero",
)
_TORCH_REDUCTION = (
    "sum", "nansum", "mean", "nanmean", "prod", "std", "var", "std_mean", "var_mean", "max", "min", "amax", "amin",
    "aminmax", "argmax", "argmin", "all", "any", "norm", "median", "nanmedian", "mode", "quantile", "nanquantile",
    "logsumexp", "cumsum", "cumprod", "cummax", "cummin", "logcumsumexp", "count_nonzero", "dist", "cdist", "pdist",
    "trace", "kthvalue", "topk", "sort", "argsort", "msort", "unique", "unique_consecutive", "bincount", "histc",
    "bucketize", "searchsorted", "diff", "gradient", "trapezoid", "trapz", "cumulative_trapezoid", "cov", "corrcoef",
    "cosine_similarity", "pairwise_distance",
)
_TORCH_SHAPE = (
    "where", "cat", "concat", "concatenate", "stack", "hstack", "vstack", "dstack", "column_stack", "row_stack",
    "reshape", "flatten", "unflatten", "squeeze", "unsqueeze", "transpose", "swapaxes", "swapdims", "permute",
    "movedim", "moveaxis", "t", "adjoint", "flip", "fliplr", "flipud", "roll", "rot90", "narrow", "select",
    "index_select", "masked_select", "masked_fill", "gather", "take", "take_along_dim", "split", "chunk",
    "tensor_split", "hsplit", "vsplit", "dsplit", "unbind", "tile", "repeat_interleave", "broadcast_to",
    "broadcast_tensors", "broadcast_shapes", "atleast_1d", "atleast_2d", "atleast_3d", "tril", "triu", "diagonal",
    "nonzero", "argwhere", "numel", "clone", "detach", "scatter", "scatter_add", "scatter_reduce", "index_add",
    "index_copy", "index_fill", "diagonal_scatter", "select_scatter", "slice_scatter", "ravel", "result_type",
    "promote_types", "can_cast",
)
_TORCH_LINALG = (
    "matmul", "mm", "bmm", "mv", "dot", "vdot", "inner", "outer", "ger", "cross", "einsum", "tensordot", "kron",
    "det", "logdet", "slogdet", "inverse", "pinverse", "matrix_power", "matrix_exp", "cholesky", "qr", "svd",
    "chain_matmul", "addmm", "addmv", "addbmm", "baddbmm",
)
_TORCH_VALUES = (
    # dtypes (also for isinstance/`dtype=`), constants, and the types reward code may name
    "float32", "float64", "float16", "bfloat16", "float", "double", "half", "int8", "int16", "int32", "int64", "int",
    "long", "short", "uint8", "bool", "complex64", "complex128", "cfloat", "cdouble",
    "pi", "e", "inf", "nan", "newaxis",
    "Tensor", "Size", "dtype", "device", "finfo", "iinfo", "no_grad",
)
TORCH_FUNCTIONS: dict[str, frozenset[str]] = {
    "torch": frozenset(_TORCH_CREATION + _TORCH_ELEMENTWISE + _TORCH_COMPARISON + _TORCH_REDUCTION + _TORCH_SHAPE
                       + _TORCH_LINALG + _TORCH_VALUES),
    "torch.linalg": frozenset({
        "norm", "vector_norm", "matrix_norm", "cross", "det", "slogdet", "inv", "pinv", "solve", "solve_triangular",
        "lstsq", "cholesky", "qr", "svd", "svdvals", "eig", "eigvals", "eigh", "eigvalsh", "matrix_rank",
        "matrix_power", "matrix_exp", "multi_dot", "vecdot", "diagonal", "cond", "tensorinv", "tensorsolve",
        "vander", "matmul", "lu", "lu_factor", "lu_solve",
    }),
    "torch.nn.functional": frozenset({
        "relu", "relu6", "elu", "selu", "celu", "gelu", "silu", "mish", "leaky_relu", "hardtanh", "hardsigmoid",
        "hardswish", "hardshrink", "softshrink", "tanhshrink", "sigmoid", "tanh", "logsigmoid", "softplus",
        "softsign", "softmax", "softmin", "log_softmax", "normalize", "cosine_similarity", "pairwise_distance",
        "pdist", "one_hot", "pad", "linear", "mse_loss", "l1_loss", "smooth_l1_loss", "huber_loss", "threshold",
        "glu",
    }),
    "torch.special": frozenset({
        "expit", "logit", "erf", "erfc", "erfcx", "erfinv", "log1p", "expm1", "exp2", "sinc", "round", "xlogy",
        "xlog1py", "entr", "ndtr", "ndtri", "log_ndtr", "i0", "i0e", "i1", "i1e", "gammaln", "digamma", "psi",
        "polygamma", "multigammaln", "softmax", "log_softmax", "logsumexp", "zeta", "gammainc", "gammaincc",
    }),
    "torch.fft": frozenset({
        "fft", "ifft", "rfft", "irfft", "fft2", "ifft2", "rfft2", "irfft2", "fftn", "ifftn", "rfftn", "irfftn",
        "hfft", "ihfft", "fftfreq", "rfftfreq", "fftshift", "ifftshift",
    }),
}
"""Module -> the names reward code may use in it: pure computations on tensors (creation from values or shapes
filled with defined values, elementwise math, comparisons, reductions, indexing and shape, linear algebra), dtypes
and constants. Submodules are reached through :data:`MODULE_MEMBERS`."""

MATH_FUNCTIONS = frozenset({
    "acos", "acosh", "asin", "asinh", "atan", "atan2", "atanh", "cbrt", "ceil", "copysign", "cos", "cosh",
    "degrees", "dist", "e", "erf", "erfc", "exp", "exp2", "expm1", "fabs", "floor", "fmod", "frexp", "fsum", "gamma",
    "gcd", "hypot", "inf", "isclose", "isfinite", "isinf", "isnan", "isqrt", "lcm", "ldexp", "lgamma", "log",
    "log10", "log1p", "log2", "modf", "nan", "nextafter", "pi", "pow", "prod", "radians", "remainder", "sin", "sinh",
    "sqrt", "tan", "tanh", "tau", "trunc", "ulp",
})
"""``math``'s pure functions and constants (not ``factorial``, ``comb``, ``perm``: unbounded work on big ints)."""

REWARD_TERMS_FUNCTIONS = frozenset({"reach", "tips_reach", "contact", "lift", "place", "fraction"})
"""The public functions of :mod:`gendex_envs.reward_terms` (a test holds the two equal)."""

MODULE_MEMBERS: dict[str, frozenset[str]] = {
    **TORCH_FUNCTIONS,
    "torch": TORCH_FUNCTIONS["torch"] | {"nn", "linalg", "special", "fft"},
    "torch.nn": frozenset({"functional"}),
    "math": MATH_FUNCTIONS,
    "gendex_envs.reward_terms": REWARD_TERMS_FUNCTIONS,
    "gendex_envs": frozenset({"reward_terms"}),
}
"""Every module reward code may reach -> the names it may use there (the runtime guard's module copies hold exactly
these; submodules by their short name)."""

VIEW_MEMBERS = frozenset({
    # RewardView
    "num_envs", "device", "table_height", "object_names", "stage_targets", "agent", "obj_pose", "obj",
    "init_obj_pos", "init_obj_quat", "obj_height", "hand_forces", "palm_pose", "tip_positions", "handle_link",
    "handle_pos", "joint_qpos", "joint_open_fraction", "holds_point", "wiped_share", "poured_share", "goal_pos",
    "spec_success",
    # PoseView, EntityView, AgentView, RobotView
    "p", "q", "raw_pose", "name", "part", "joint", "pose", "linear_velocity", "angular_velocity", "robot",
    "get_hand_group_obj_mean_force", "get_qpos", "get_qvel",
})
"""The public members of the env view and the views it returns (:mod:`gendex_envs.reward_view`; a test holds the
two equal, and ``prompts/env_api.txt`` documents them)."""

TENSOR_METHODS = frozenset({
    # what a tensor is
    "shape", "dtype", "device", "ndim", "T", "mT", "real", "imag", "is_cuda", "is_floating_point", "is_complex",
    "size", "dim", "numel", "nelement", "item", "tolist",
    # conversions (to a dtype or device: a new tensor)
    "float", "double", "half", "int", "long", "short", "bool", "to", "cpu", "type", "type_as", "clone", "detach",
    "contiguous", "new_tensor", "new_zeros", "new_ones", "new_full",
    # shape and indexing
    "view", "view_as", "reshape", "reshape_as", "expand", "expand_as", "broadcast_to", "unsqueeze", "squeeze",
    "flatten", "unflatten", "ravel", "transpose", "permute", "t", "movedim", "swapaxes", "flip", "roll", "repeat",
    "repeat_interleave", "tile", "narrow", "select", "index_select", "masked_select", "masked_fill", "gather",
    "take", "take_along_dim", "split", "chunk", "unbind", "unfold", "diagonal", "tril", "triu", "where", "nonzero",
    "argwhere", "scatter", "scatter_add", "index_add", "index_fill",
    # elementwise math and comparisons
    "clamp", "clip", "clamp_min", "clamp_max", "abs", "absolute", "neg", "negative", "sign", "sgn", "signbit",
    "sqrt", "rsqrt", "square", "exp", "exp2", "expm1", "log", "log1p", "log2", "log10", "sin", "cos", "tan", "asin",
    "acos", "atan", "atan2", "sinh", "cosh", "tanh", "sigmoid", "logit", "relu", "softmax", "log_softmax", "erf",
    "lgamma", "sinc", "floor", "ceil", "round", "trunc", "frac", "reciprocal", "pow", "add", "sub", "mul", "div",
    "true_divide", "floor_divide", "remainder", "fmod", "hypot", "lerp", "nan_to_num", "deg2rad", "rad2deg",
    "copysign", "heaviside", "angle", "conj", "addcmul", "addcdiv", "eq", "ne", "lt", "le", "gt", "ge",
    "maximum", "minimum", "fmax", "fmin", "isclose", "allclose", "equal", "isfinite", "isinf", "isnan",
    "logical_and", "logical_or", "logical_not", "logical_xor", "bitwise_and", "bitwise_or", "bitwise_xor",
    "bitwise_not",
    # reductions and linear algebra
    "sum", "nansum", "mean", "nanmean", "prod", "std", "var", "max", "min", "amax", "amin", "aminmax", "argmax",
    "argmin", "all", "any", "norm", "cumsum", "cumprod", "cummax", "cummin", "logsumexp", "median", "quantile",
    "mode", "topk", "sort", "argsort", "kthvalue", "unique", "count_nonzero", "diff", "trace", "matmul", "mm",
    "bmm", "mv", "dot", "cross", "outer", "det", "inverse",
})
"""Methods and attributes of a tensor reward code may use: none that exposes memory (``storage``,
``untyped_storage``, ``data_ptr``, ``as_strided``, ``numpy``), writes files (``tofile`` through ``numpy``), hands
out uninitialised memory (``new_empty``) or changes a tensor in place (every ``*_`` method, ``set_``,
``resize_``). Tensor methods cannot be withheld in-process (every tensor has them), so the static check is what
enforces this list; the confined worker process is the wall behind it (:mod:`gendex_envs.guard`)."""

RESULT_FIELDS = frozenset({
    "values", "indices", "eigenvalues", "eigenvectors", "U", "S", "Vh", "Q", "R", "L", "LU", "pivots", "sign",
    "logabsdet", "solution", "residuals", "rank", "singular_values", "mantissa", "exponent", "mean", "std",
    # torch.finfo / iinfo, torch.device, torch.dtype
    "eps", "tiny", "bits", "resolution", "smallest_normal", "index", "is_signed", "itemsize",
})
"""Fields of what allowed torch functions return (``torch.max(x, dim=1).values``, ``torch.finfo(t.dtype).eps``,
``env.device.type``)."""

CONTAINER_METHODS = frozenset({
    "get", "items", "keys", "values", "copy", "index", "count", "union", "intersection", "difference",
    "symmetric_difference", "issubset", "issuperset", "isdisjoint", "startswith", "endswith", "lower", "upper",
    "strip", "lstrip", "rstrip", "split", "join",
})
"""Reading methods of dicts (``info``, ``obs``), lists, tuples, sets and strings. Their mutators
(:data:`CONTAINER_MUTATORS`) are allowed only on containers the function created."""

REQUIRED_FUNCTIONS = {"evaluate": ("env",), "compute_dense_reward": ("env", "obs", "action", "info")}
OPTIONAL_FUNCTIONS = {"_get_obs_extra": ("env", "info")}

ALLOWED_BUILTINS = frozenset({
    "abs", "all", "any", "bool", "dict", "divmod", "enumerate", "filter", "float", "int",
    "isinstance", "len", "list", "map", "max", "min", "pow", "range", "reversed", "round", "slice", "sorted",
    "str", "sum", "tuple", "zip", "getattr", "hasattr",
    "ArithmeticError", "AssertionError", "Exception", "IndexError", "KeyError", "LookupError",
    "NotImplementedError", "RuntimeError", "TypeError", "ValueError", "ZeroDivisionError",
})
"""Builtins reward code may use (``getattr``/``hasattr`` only with a literal attribute name). Not ``set`` or
``frozenset``: a set of strings iterates in an order that changes with each process's hash seed, so the same module
would give other rewards in the sandbox's worker, in another run, or on another machine; tuples and lists keep
their order."""

BUILTIN_REASONS = {
    "set": "sets iterate in an order that changes from process to process; use a tuple or a list",
    "frozenset": "sets iterate in an order that changes from process to process; use a tuple",
}
"""Why some builtins outside :data:`ALLOWED_BUILTINS` are refused (others get the list of allowed ones)."""
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
    "BoolOp", "BinOp", "UnaryOp", "Lambda", "IfExp", "Dict", "ListComp", "DictComp",
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
    "Set": "sets iterate in an order that changes from process to process; use a tuple or a list",
    "SetComp": "sets iterate in an order that changes from process to process; use a list comprehension",
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
    "zeros", "ones", "full", "zeros_like", "ones_like", "full_like", "arange", "linspace", "eye", "tensor", "stack",
    "cat", "where", "clone",
})
"""``torch.<f>(...)`` always returns a new tensor: a local bound to it may be written by subscript."""
FRESH_METHODS = frozenset({
    "clone", "to", "float", "double", "half", "int", "long", "bool", "contiguous", "view", "view_as", "reshape",
    "expand", "expand_as", "unsqueeze", "squeeze", "flatten", "transpose", "permute", "t", "detach", "repeat",
})
"""``x.<m>(...)`` is new (``clone``) or shares memory only with ``x``: fresh when ``x`` is."""
FRESH_BUILTINS = frozenset({"list", "dict", "tuple", "sorted", "len", "float", "int", "bool", "range",
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

VALUE_ATTRIBUTES = TENSOR_METHODS | VIEW_MEMBERS | RESULT_FIELDS | CONTAINER_METHODS | CONTAINER_MUTATORS
"""Every attribute name reward code may use on a value that is not a module (the static check cannot know a
value's type, so a name is allowed on any value when some allowed type has it)."""
ALLOWED_ATTRIBUTE_NAMES = VALUE_ATTRIBUTES.union(*MODULE_MEMBERS.values())
"""Every attribute name reward code may use at all (the runtime ``getattr``/``hasattr`` refuse the rest)."""

ALTERNATIVES: dict[str, tuple[str, ...]] = {
    "empty": ("zeros", "full"), "empty_like": ("zeros_like", "full_like"), "empty_strided": ("zeros",),
    "new_empty": ("new_zeros", "new_full"), "asarray": ("as_tensor", "tensor"), "frombuffer": ("tensor",),
    "from_numpy": ("tensor",), "as_strided": ("view", "reshape", "unfold"), "numpy": ("tolist", "item"),
    "rand": ("linspace",), "randn": ("zeros",), "rand_like": ("zeros_like",), "randn_like": ("zeros_like",),
}
"""What to use instead of a refused name (named first in the refusal, before the nearest spellings)."""
