"""Replaying a recorded reward call in the parent, through the op table only (parent side).

The confined worker records a reward function's call as a graph (:mod:`gendex_envs.sandbox.trace`). The graph is
untrusted data: :func:`compile_graph` checks every entry before anything runs, and the parent then evaluates the
function on later steps from the graph, in this process, without a round trip to the worker. What a replay can do:

* call an operation of :data:`gendex_envs.sandbox.ops.OPS` (allow-listed torch math; no file, storage, raw memory,
  RNG or global state), with constants of a few plain types and earlier results as arguments; no ``out=``;
* read the env members and argument entries the graph names (the same members the worker may ask for), each as a
  fresh copy: in-place operations of a replay change only its own tensors;
* nothing else: there is no name lookup, no attribute access and no Python code of the module in a replay.

Bounds, checked before a graph is kept: at most :data:`MAX_ENTRIES` entries; every result's size is stated and
each at most :data:`MAX_NODE_ELEMENTS` (scaled by the number of envs), all together at most
:data:`MAX_GRAPH_ELEMENTS`; the stated sizes are proven by running the graph once on fake tensors (shapes
without data, memory or work), so an operation whose size would come from tensor values, or that states a size
it would not have, refuses the graph. Operations whose size arguments are tensors are refused
(:data:`ops.SHAPE_ARGUMENTS`). With every input's shape fixed, a replay does the work the graph states, no more.

At replay, a leaf whose shape or dtype differs, a result that differs from what the graph states, a guard (a Python
value the recorded call depended on, such as ``bool(x.any())``) that comes out otherwise, or any error, is a
:class:`Miss`: the caller asks the worker instead (:class:`gendex_envs.sandbox.host.RemoteModule`).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Mapping

import torch

from gendex_envs.sandbox import ops
from gendex_envs.sandbox.protocol import DTYPES

MAX_ENTRIES = 1024
"""Leaves plus operations of a graph (committed reward functions make 20-150)."""
SHAPE_CHECK_S = 0.5
"""Wall-clock budget of the fake-tensor run that proves a graph's shapes (committed graphs: 10-60 ms; torch's
one-time set-up of fake tensors, about 1 s, is done before it starts)."""
MAX_NODE_ELEMENTS_PER_ENV = 4096
"""A result may hold this many elements per env (a committed reward function's largest is 18: ``[N, 6, 3]``)."""
MAX_NODE_ELEMENTS = 1 << 16
"""... and at least this many, whatever the number of envs."""
MAX_GRAPH_ELEMENTS = 16
"""All results together hold at most this many times the per-result bound (with the costliest operations left to
the worker, :data:`gendex_envs.sandbox.ops.NOT_REPLAYED`, this keeps a replay well under a second)."""
MAX_WORK = 1 << 24
MAX_WORK_PER_ENV = 1 << 14
"""The work of a graph: the elements each operation reads and writes, summed over operations (an input used by many
operations counts each time), weighted (:func:`_work`); at most this many per env and :data:`MAX_WORK` at
least. A committed reward function's graph does about 3 000 per env."""
MAX_CONST_BYTES = 1 << 20
"""Constant tensors of one graph (module-level constants the call used; the recorder sends at most as much)."""
MAX_PATH = 16
_DTYPES = {**DTYPES, "complex64": torch.complex64, "complex128": torch.complex128}
FORBIDDEN_KEYWORDS = frozenset({"out", "inplace", "pin_memory", "requires_grad", "layout", "memory_format", "names"})
"""Keywords a replayed operation may not get: results into other tensors, autograd, memory placement."""


class GraphError(ValueError):
    """A recorded graph that breaks the format, names an operation outside the table, or breaks a bound."""


class Miss(Exception):
    """This replay does not reproduce the recorded call (a leaf, a result or a guard differs, or an error)."""


class _Ref:
    __slots__ = ("i", "j")

    def __init__(self, i: int, j: int | None):
        self.i, self.j = i, j


class _Const:
    """A tensor of the graph (a module-level constant): each replay gets its own copy."""

    __slots__ = ("t",)

    def __init__(self, t: torch.Tensor):
        self.t = t


_DEVICE = object()


def _shape(raw) -> tuple[int, ...]:
    if not (isinstance(raw, list) and len(raw) <= 8 and all(type(d) is int and 0 <= d < 2**40 for d in raw)):
        raise GraphError(f"bad shape {str(raw)[:100]}")
    return tuple(raw)


def _dtype(raw) -> torch.dtype:
    if not (isinstance(raw, str) and raw in _DTYPES):
        raise GraphError(f"bad dtype {str(raw)[:50]}; allowed: {sorted(_DTYPES)}")
    return _DTYPES[raw]


class _Decoder:
    def __init__(self, kinds: list):
        self.kinds = kinds  # per entry: ("T",) or ("S", n) or ("V",) / ("N",)
        self.const_bytes = 0

    def value(self, raw, depth: int = 0):
        kind = type(raw)
        if raw is None or kind is bool or kind is int or kind is str:
            return raw
        if kind is float:
            return raw
        if depth > 16:
            raise GraphError("value nested deeper than 16 levels")
        if kind is dict:
            return {self._key(k): self.value(v, depth + 1) for k, v in raw.items()}
        if isinstance(raw, torch.Tensor):
            raise GraphError("a tensor outside a constant")
        if not (kind is list and raw and type(raw[0]) is str):
            raise GraphError(f"untagged value {str(raw)[:100]}")
        tag, rest = raw[0], raw[1:]
        if tag == "$r":
            if not (len(rest) == 2 and type(rest[0]) is int and 0 <= rest[0] < len(self.kinds)
                    and (rest[1] is None or type(rest[1]) is int)):
                raise GraphError(f"bad reference {str(raw)[:100]}")
            kind_of = self.kinds[rest[0]]
            if not (rest[1] is None and kind_of[0] == "T" or kind_of[0] == "S" and type(rest[1]) is int
                    and 0 <= rest[1] < kind_of[1]):
                raise GraphError(f"reference {str(raw)[:100]} to a result that is not a tensor")
            return _Ref(rest[0], rest[1])
        if tag == "$c":
            if not (len(rest) == 1 and isinstance(rest[0], torch.Tensor)):
                raise GraphError("bad constant tensor")
            self.const_bytes += rest[0].numel() * rest[0].element_size()
            if self.const_bytes > MAX_CONST_BYTES:
                raise GraphError(f"more than {MAX_CONST_BYTES} bytes of constant tensors")
            return _Const(rest[0].clone())  # its own storage, not a view that keeps the whole frame alive
        if tag in ("$l", "$u"):
            items = [self.value(v, depth + 1) for v in rest]
            return items if tag == "$l" else tuple(items)
        if tag == "$z":
            return torch.Size(_shape(list(rest)))
        if tag == "$s" and len(rest) == 3:
            start, stop, step = (self.value(v, depth + 1) for v in rest)
            return slice(start, stop, step)
        if tag == "$e" and not rest:
            return Ellipsis
        if tag == "$dt" and len(rest) == 1:
            return _dtype(rest[0])
        if tag == "$dev" and not rest:
            return _DEVICE
        raise GraphError(f"unknown value tag {str(tag)[:20]}")

    @staticmethod
    def _key(k):
        if type(k) is not str or len(k) > 256:
            raise GraphError("bad keyword")
        return k


def _holds(value, cls) -> bool:
    if isinstance(value, cls):
        return True
    if isinstance(value, list | tuple):
        return any(_holds(v, cls) for v in value)
    if isinstance(value, dict):
        return any(_holds(v, cls) for v in value.values())
    if isinstance(value, slice):
        return any(_holds(v, cls) for v in (value.start, value.stop, value.step))
    return False


def _binder(value, device, const: Callable | None = None) -> Callable[[list], object]:
    """A function of the replay's results (``vals``) that builds ``value``, the device placeholder resolved;
    ``const(t)`` makes a constant tensor's master copy (default: ``t`` on ``device``), each replay getting a clone."""
    if not _holds(value, (_Ref, _Const)):
        fixed = _resolve_device(value, device)
        return lambda vals: fixed
    if isinstance(value, _Ref):
        i, j = value.i, value.j
        return (lambda vals: vals[i]) if j is None else (lambda vals: vals[i][j])
    if isinstance(value, _Const):
        t = value.t.to(device) if const is None else const(value.t)
        return lambda vals: t.clone()
    if type(value) is tuple and all(isinstance(v, _Ref) and v.j is None or not _holds(v, (_Ref, _Const))
                                    for v in value):
        return _flat_tuple(value, device)
    if isinstance(value, list | tuple):
        parts, make = [_binder(v, device, const) for v in value], type(value)
        return lambda vals: make([p(vals) for p in parts])
    if isinstance(value, dict):
        named = [(k, _binder(v, device, const)) for k, v in value.items()]
        return lambda vals: {k: p(vals) for k, p in named}
    if isinstance(value, slice):
        parts = [_binder(v, device, const) for v in (value.start, value.stop, value.step)]
        return lambda vals: slice(*[p(vals) for p in parts])
    raise GraphError(f"cannot bind {type(value).__name__}")  # pragma: no cover (the decoder makes no other)


def _flat_tuple(value: tuple, device) -> Callable[[list], tuple]:
    """A binder for the usual arguments: earlier results and constants side by side (``(x, 2.0)``, ``(a, b)``)."""
    refs = [(k, v.i) for k, v in enumerate(value) if isinstance(v, _Ref)]
    fixed = [None if isinstance(v, _Ref) else _resolve_device(v, device) for v in value]
    if len(value) == 1:
        i = refs[0][1]
        return lambda vals: (vals[i],)
    if len(value) == 2 and len(refs) == 2:
        i, k = refs[0][1], refs[1][1]
        return lambda vals: (vals[i], vals[k])
    if len(value) == 2 and refs[0][0] == 0:
        i, c = refs[0][1], fixed[1]
        return lambda vals: (vals[i], c)
    if len(value) == 2:
        c, i = fixed[0], refs[0][1]
        return lambda vals: (c, vals[i])

    def bind(vals):
        out = fixed.copy()
        for k, i in refs:
            out[k] = vals[i]
        return tuple(out)
    return bind


def _resolve_device(value, device):
    if value is _DEVICE:
        return device
    if isinstance(value, torch.Size):
        return value
    if isinstance(value, list | tuple):
        return type(value)([_resolve_device(v, device) for v in value])
    if isinstance(value, dict):
        return {k: _resolve_device(v, device) for k, v in value.items()}
    return value


class Graph:
    """A checked graph of one reward function's call: :meth:`run` replays it on the current state."""

    def __init__(self, steps: list, out, leaves: int, ops_count: int, device):
        self.steps, self._out, self.leaves, self.ops, self.device = steps, out, leaves, ops_count, device

    def run(self, view, args: tuple):
        """The function's value on the current state of ``view`` (the env's reward view) with the call's ``args``.
        Raises :class:`Miss` when the replay does not reproduce the recorded call."""
        vals: list = [None] * len(self.steps)
        tensor = torch.Tensor
        try:
            for i, step in enumerate(self.steps):
                if step[0] == 0:  # a leaf: the real view's member or the argument's entry, copied
                    _, read, dtype, shape, source = step
                    t = read(view, args)
                    if not (isinstance(t, tensor) and t.dtype == dtype and t.shape == shape):
                        raise Miss(f"leaf {source} is not {dtype} {list(shape)}")
                    vals[i] = t.clone()
                    continue
                _, fn, bind_args, bind_kwargs, stated, check = step
                out = fn(*bind_args(vals), **bind_kwargs(vals)) if bind_kwargs else fn(*bind_args(vals))
                if stated is not None:
                    if type(out) is not tensor or out.dtype != stated[0] or out.shape != stated[1]:
                        raise Miss(f"a result is not {stated[0]} {list(stated[1])}")
                else:
                    check(out)
                vals[i] = out
            value = self._out(vals)
            if not _on(value, self.device):
                raise Miss("a returned tensor is not on the env's device, or requires grad")
            return value
        except Miss:
            raise
        except Exception as exc:  # an error the worker would report with the module's line: let it
            raise Miss(f"{type(exc).__name__}: {str(exc)[:200]}") from None


def _on(value, device, depth: int = 0) -> bool:
    """Every tensor in ``value`` lies on ``device`` and does not require grad."""
    if isinstance(value, torch.Tensor):
        here = value.device
        return (here.type == device.type and (device.index is None or here.index == device.index)
                and not value.requires_grad)
    if depth > 16:
        return False
    if isinstance(value, dict):
        return all(_on(v, device, depth + 1) for v in value.values())
    if isinstance(value, list | tuple):
        return all(_on(v, device, depth + 1) for v in value)
    return True


def _checker(spec_kind, spec):
    """A function that raises :class:`Miss` unless a result matches its stated spec."""
    if spec_kind == "T":
        dtype, shape = spec

        def check(out):
            if not (type(out) is torch.Tensor and out.dtype == dtype and out.shape == shape):
                raise Miss(f"a result is not {dtype} {list(shape)}")
        return check
    if spec_kind == "S":
        specs = spec

        def check(out):
            if not (isinstance(out, tuple | list) and len(out) == len(specs)):
                raise Miss("a result is not the stated sequence")
            for x, (dtype, shape) in zip(out, specs, strict=True):
                if not (type(x) is torch.Tensor and x.dtype == dtype and x.shape == shape):
                    raise Miss(f"a result is not {dtype} {list(shape)}")
        return check
    if spec_kind == "N":
        def check(out):
            if out is not None:
                raise Miss("a result is not None")
        return check
    expected = spec
    if expected is _DEVICE:
        def check(out):
            if not isinstance(out, torch.device):
                raise Miss("a result is not a device")
        return check

    def check(out):
        if not _exactly(out, expected):
            raise Miss(f"guard {str(expected)[:60]} came out {str(out)[:60]}")
    return check


def _exactly(a, b) -> bool:
    """``a`` is ``b`` as a value: the same type, floats bit for bit (``-0.0`` is not ``0.0``, NaN is NaN), inside
    tuples and lists too."""
    if type(a) is not type(b):
        return False
    if type(a) is float:
        return a.hex() == b.hex() if not (math.isnan(a) and math.isnan(b)) else True
    if isinstance(a, tuple | list) and not isinstance(a, torch.Size):
        return len(a) == len(b) and all(_exactly(x, y) for x, y in zip(a, b, strict=True))
    return a == b


def _spec(raw) -> tuple:
    if not (isinstance(raw, list) and raw and raw[0] in ("T", "S", "V", "N")):
        raise GraphError(f"bad result spec {str(raw)[:100]}")
    if raw[0] == "T" and len(raw) == 3:
        return "T", (_dtype(raw[1]), _shape(raw[2]))
    if raw[0] == "S" and len(raw) == 2 and isinstance(raw[1], list) and 0 < len(raw[1]) <= 64:
        parts = [_spec(x) for x in raw[1]]
        if any(p[0] != "T" for p in parts):
            raise GraphError("a sequence result holds something other than tensors")
        return "S", [p[1] for p in parts]
    if raw[0] == "N" and len(raw) == 1:
        return "N", None
    if raw[0] == "V" and len(raw) == 2:
        return "V", raw[1]
    raise GraphError(f"bad result spec {str(raw)[:100]}")


def compile_graph(raw, num_envs: int, device, source_reader: Callable[[list], Callable]) -> Graph:
    """``raw`` (a decoded graph from the worker) checked and bound to ``device``; raises :class:`GraphError`.
    ``source_reader(source)`` gives the function ``(view, args) -> tensor`` that reads a leaf's source, and raises
    (``TypeError``/``ValueError``) for a source the parent would not read."""
    if not (isinstance(raw, dict) and set(raw) == {"entries", "out"} and isinstance(raw["entries"], list)):
        raise GraphError("a graph is an object with entries and out, and nothing else")
    entries = raw["entries"]
    if len(entries) > MAX_ENTRIES:
        raise GraphError(f"{len(entries)} entries; at most {MAX_ENTRIES}")
    node_cap = max(MAX_NODE_ELEMENTS, MAX_NODE_ELEMENTS_PER_ENV * max(1, int(num_envs)))
    total_cap, total = MAX_GRAPH_ELEMENTS * node_cap, 0
    work_cap, work = max(MAX_WORK, MAX_WORK_PER_ENV * max(1, int(num_envs))), 0
    kinds: list = []
    decoder = _Decoder(kinds)
    parsed: list = []
    n_leaves = 0
    for entry in entries:
        if not (isinstance(entry, list) and entry and entry[0] in ("L", "O")):
            raise GraphError(f"bad entry {str(entry)[:100]}")
        if entry[0] == "L":
            if len(entry) != 4 or not isinstance(entry[1], list) or not 1 <= len(entry[1]) <= MAX_PATH:
                raise GraphError(f"bad leaf {str(entry)[:100]}")
            source = entry[1]
            try:
                read = source_reader(source)
            except (TypeError, ValueError) as exc:
                raise GraphError(f"leaf {str(source)[:100]}: {exc}") from None
            dtype, shape = _dtype(entry[2]), _shape(entry[3])
            total += _elements(shape, node_cap)
            parsed.append(("L", source, dtype, shape, read))
            kinds.append(("T",))
            n_leaves += 1
            continue
        if len(entry) != 5:
            raise GraphError(f"bad operation {str(entry)[:100]}")
        name = entry[1]
        if not (isinstance(name, str) and name in ops.OPS):
            raise GraphError(f"operation {str(name)[:100]} is not one a replay may run")
        args, kwargs = decoder.value(entry[2]), decoder.value(entry[3])
        if not (isinstance(args, tuple) and isinstance(kwargs, dict)):
            raise GraphError(f"{name}: bad arguments")
        if FORBIDDEN_KEYWORDS & set(kwargs):
            raise GraphError(f"{name}: keywords {sorted(FORBIDDEN_KEYWORDS & set(kwargs))} are not replayed")
        if "device" in kwargs and kwargs["device"] is not _DEVICE:
            raise GraphError(f"{name}: a device other than the env's")
        if name in ("Tensor.to", "Tensor.type") and any(isinstance(a, str) for a in args[1:]):
            raise GraphError(f"{name}: a device or type named by a string")
        if ops.takes_shape_arguments(name) and (_holds(args[1:], (_Ref, _Const)) or _holds(kwargs, (_Ref, _Const))):
            raise GraphError(f"{name}: its sizes must be constants, not tensors")
        kind, spec = _spec(entry[4])
        if (kind == "V") != ops.is_guard(name):
            raise GraphError(f"{name} states a {'Python value' if kind == 'V' else 'tensor'} result; it gives "
                             f"{'a tensor' if kind == 'V' else 'a Python value'}")
        if kind == "N" and name != "Tensor.__setitem__":
            raise GraphError(f"{name} states no result")
        if kwargs.get("rounding_mode") == "trunc" and not (kind == "T" and spec[0].is_floating_point):
            raise GraphError(f"{name}: integer division rounding to zero is not replayed (its overflow traps)")
        if kind == "T":
            total += _elements(spec[1], node_cap)
            kinds.append(("T",))
        elif kind == "S":
            total += sum(_elements(s, node_cap) for _, s in spec)
            kinds.append(("S", len(spec)))
        else:
            kinds.append((kind,))
            if kind == "V":
                spec = decoder.value(spec)
                if _holds(spec, (_Ref, _Const)):
                    raise GraphError(f"{name}: a guard holds a tensor")
        if total > total_cap:
            raise GraphError(f"the graph's results hold more than {total_cap} elements")
        work += _work(name, args, kwargs, kind, spec, parsed)
        if work > work_cap:
            raise GraphError(f"the graph's operations touch more than {work_cap} elements (their inputs and results, "
                             f"weighted by the cost of the operation)")
        parsed.append(("O", name, args, kwargs, kind, spec))
    out = decoder.value(raw["out"])
    _shape_check(parsed, out)
    steps: list = []
    for p in parsed:
        if p[0] == "L":
            steps.append((0, p[4], p[2], torch.Size(p[3]), p[1]))
            continue
        _, name, args, kwargs, kind, spec = p
        stated = None
        if kind == "T":
            spec = stated = (spec[0], torch.Size(spec[1]))
        elif kind == "S":
            spec = [(d, torch.Size(s)) for d, s in spec]
        steps.append((1, ops.OPS[name], _binder(args, device), _binder(kwargs, device) if kwargs else None, stated,
                      _checker(kind, spec)))
    return Graph(steps, _binder(out, device), n_leaves, len(steps) - n_leaves, torch.device(device))


_SORTING = frozenset({"sort", "argsort", "msort", "median", "nanmedian", "quantile", "nanquantile", "kthvalue", "topk",
                      "mode"})
_CONTRACTING = frozenset({"matmul", "mm", "bmm", "mv", "dot", "vdot", "inner", "addmm", "addmv", "addbmm", "baddbmm",
                          "linear", "cdist", "__matmul__", "__rmatmul__", "cov", "corrcoef", "pdist"})
_NORMS = frozenset({"norm", "vector_norm", "dist"})


def _work(name: str, args, kwargs, kind: str, spec, parsed: list) -> int:
    """An upper estimate of the elements ``name`` touches, from the shapes the graph states: its inputs and
    results, times log n for sorting and selection, times the contracted length for products, and as if every norm
    with an order were a matrix norm (a decomposition: n^1.5)."""
    shapes: list[tuple] = []

    def walk(v):
        if isinstance(v, _Ref):
            p = parsed[v.i]
            shapes.append(p[3] if p[0] == "L" else (p[5][1] if v.j is None else p[5][v.j][1]))
        elif isinstance(v, _Const):
            shapes.append(tuple(v.t.shape))
        elif isinstance(v, list | tuple):
            for x in v:
                walk(x)
        elif isinstance(v, dict):
            for x in v.values():
                walk(x)
        elif isinstance(v, slice):
            walk([v.start, v.stop, v.step])

    walk(args)
    walk(kwargs)
    inputs = sum(math.prod(sh) for sh in shapes)
    out = math.prod(spec[1]) if kind == "T" else sum(math.prod(sh) for _, sh in spec) if kind == "S" else 1
    base = inputs + out + _broadcast(shapes)
    short = name.rsplit(".", 1)[-1]
    if short in _SORTING:
        return base * max(1, math.ceil(math.log2(max(2, inputs))))
    if short in _CONTRACTING:
        inner = shapes[0][-1] if shapes and shapes[0] else 1
        return base + out * max(1, inner) * (inner if short in ("cov", "corrcoef", "pdist") else 1)
    if short in _NORMS and (len(args) > 1 or "ord" in kwargs or "p" in kwargs):
        return base + math.ceil(inputs ** 1.5)
    if short.startswith(("fft", "ifft", "rfft", "irfft", "hfft", "ihfft")):
        return base * max(1, math.ceil(math.log2(max(2, inputs))))
    return base


def _broadcast(shapes: list[tuple]) -> int:
    """Elements of the broadcast of the inputs (what an elementwise operation, a loss or an indexed assignment
    touches inside, whatever its result's size), or of all inputs but the first (index tensors of a subscript)."""
    for group in (shapes, shapes[1:]):
        if len(group) > 1:
            try:
                return math.prod(torch.broadcast_shapes(*group))
            except (RuntimeError, ValueError, TypeError):
                continue
    return 0


def _elements(shape: tuple, cap: int) -> int:
    n = math.prod(shape)
    if n > cap:
        raise GraphError(f"a result of shape {list(shape)} holds more than {cap} elements")
    return n


def _shape_check(parsed: list, out) -> None:
    """Run the graph on fake tensors (shapes and dtypes, no data, no memory, no work: torch's ``FakeTensorMode``):
    every stated result must be what the operation gives. An operation whose result would depend on data (a mask,
    ``nonzero``) or that fake tensors cannot run refuses the graph; a guard on data keeps its stated value (the
    replay checks it on the real values)."""
    from torch._subclasses.fake_tensor import FakeTensorMode

    cpu = torch.device("cpu")
    vals: list = [None] * len(parsed)
    quiet = logging.getLogger("torch._subclasses.fake_tensor")
    level = quiet.level
    quiet.setLevel(logging.CRITICAL)  # a kernel that cannot run on fake tensors logs its whole traceback
    try:
        _warm_fake_tensors(FakeTensorMode)
        deadline = time.monotonic() + SHAPE_CHECK_S
        _shape_run(parsed, out, vals, cpu, deadline, FakeTensorMode)
    finally:
        quiet.setLevel(level)


_WARM: list[bool] = []


def _warm_fake_tensors(fake_mode) -> None:
    """torch's first fake-tensor run in a process sets itself up (about 1 s): once, outside any graph's budget."""
    if not _WARM:
        with fake_mode():
            (torch.empty(2, 3) + 1.0).sum(-1)
        _WARM.append(True)


def _shape_run(parsed: list, out, vals: list, cpu, deadline: float, fake_mode) -> None:
    with fake_mode(allow_non_fake_inputs=False) as mode:
        for i, p in enumerate(parsed):
            if time.monotonic() > deadline:
                raise GraphError(f"proving the graph's shapes took more than {SHAPE_CHECK_S} s")
            if p[0] == "L":
                vals[i] = torch.empty(p[3], dtype=p[2])
                continue
            _, name, args, kwargs, kind, spec = p
            try:
                a = _binder(args, cpu, mode.from_tensor)(vals)
                k = _binder(kwargs, cpu, mode.from_tensor)(vals)
                result = ops.OPS[name](*a, **k)
            except Exception as exc:
                if kind != "V":
                    raise GraphError(f"{name} cannot be checked without data ({type(exc).__name__}: "
                                     f"{str(exc)[:150]})") from None
                result = spec  # a guard on data: the replay checks it on the real values
            if kind == "T":
                if not (isinstance(result, torch.Tensor) and result.dtype == spec[0]
                        and tuple(result.shape) == spec[1]):
                    raise GraphError(f"{name} states a result it does not give")
            elif kind == "S":
                if not (isinstance(result, tuple | list) and len(result) == len(spec) and all(
                        isinstance(x, torch.Tensor) and x.dtype == d and tuple(x.shape) == s
                        for x, (d, s) in zip(result, spec, strict=True))):
                    raise GraphError(f"{name} states results it does not give")
            elif kind == "N" and result is not None:
                raise GraphError(f"{name} states no result but gives one")
            elif kind == "V" and _holds(result, torch.Tensor):
                raise GraphError(f"{name} states a Python value but gives a tensor")
            vals[i] = result
        _binder(out, cpu, mode.from_tensor)(vals)


# ---------------------------------------------------------------------------------------------- call signatures
def signature(value, depth: int = 0):
    """What a recorded call's Python logic may have seen of an argument besides the tensors it read: the structure
    (keys, lengths), tensor dtypes and shapes, and every other value. Graphs are kept per signature."""
    if isinstance(value, torch.Tensor):
        return ("t", value.dtype, tuple(value.shape))
    if depth > 16:
        return ("deep",)
    if isinstance(value, Mapping):
        return ("d", tuple((k, signature(v, depth + 1)) for k, v in value.items()))
    if isinstance(value, list | tuple):
        return (type(value).__name__, tuple(signature(v, depth + 1) for v in value))
    if type(value) is float:
        return ("v", "float", value.hex())  # -0.0 and 0.0 differ; NaN equals NaN
    if value is None or isinstance(value, bool | int | str):
        return ("v", type(value).__name__, value)
    return ("o", type(value).__name__)
