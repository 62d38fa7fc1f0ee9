"""Recording a reward call in the confined worker as a straight-line graph of torch operations (worker side).

While a reward function runs under a :class:`Tracer` (a ``TorchFunctionMode``), every torch call it makes (a torch
function, a tensor method, an operator, a tensor attribute) is recorded as one entry: the operation's name in
:data:`gendex_envs.sandbox.ops.OPS`, its arguments (earlier results by reference, everything else as a constant) and
what it returned (a tensor's dtype and shape; a Python value such as ``bool(x.any())`` or ``x.shape`` as a *guard*
the replay must reproduce). A tensor the call reads from the env view or its arguments becomes a *leaf* entry
naming where it came from, at the point it is first used. Python-level logic (loops over names, constants,
branches on static values) runs once and leaves only its torch calls behind.

The recording is data for the parent, not code: the parent checks it and replays it only through the op table
(:mod:`gendex_envs.sandbox.replay`). A call that does something the table lacks, passes a value the format cannot
state, or grows past the bounds is simply not recorded (``{"failed": why}``); it still runs and returns as usual.
"""

from __future__ import annotations

import torch
from torch.overrides import TorchFunctionMode

from gendex_envs.sandbox.ops import NAMES

MAX_ENTRIES = 1024
"""Leaves plus operations of one recorded call (a committed reward function makes 20-150 torch calls)."""
MAX_CONST_BYTES = 1 << 20
"""Tensors the call uses that it did not read or compute (module-level constants) travel with the graph."""
MAX_STR_CHARS = 256
MAX_SEQUENCE = 4096


class Untraceable(Exception):
    """A value or an operation the graph format cannot state."""


def sources_of(value, prefix: tuple, into: dict[int, tuple], keep: list, depth: int = 0) -> None:
    """``into[id(tensor)] = prefix + path`` for every tensor inside ``value`` (dicts by key, lists by index)."""
    if depth > 16:
        return
    if isinstance(value, torch.Tensor):
        into.setdefault(id(value), prefix)
        keep.append(value)
    elif isinstance(value, dict):
        for k, v in value.items():
            if isinstance(k, str):
                sources_of(v, (*prefix, k), into, keep, depth + 1)
    elif isinstance(value, list | tuple):
        for i, v in enumerate(value):
            sources_of(v, (*prefix, i), into, keep, depth + 1)


def _holds_tensor(value, depth: int = 0) -> bool:
    if isinstance(value, torch.Tensor):
        return True
    if isinstance(value, list | tuple) and depth < 16:
        return any(_holds_tensor(v, depth + 1) for v in value)
    if isinstance(value, dict) and depth < 16:
        return any(_holds_tensor(v, depth + 1) for v in value.values())
    return False


class Tracer(TorchFunctionMode):
    """Records the torch calls made while it is active (``with tracer: ...``); :meth:`finish` gives the graph.

    ``sources``: ``id(tensor) -> where it came from`` (``("m", member, *args)`` for an env member of the call's
    snapshot, ``("a", i, *path)`` for a tensor inside the i-th argument); :meth:`source` adds members fetched
    during the call."""

    def __init__(self, sources: dict[int, tuple], keep: list):
        super().__init__()
        self.sources, self.keep = sources, keep
        self.entries: list = []
        self.refs: dict[int, list] = {}
        self.failed: str | None = None
        self.const_bytes = 0
        self.paused = False  # while the worker talks to the parent (decoding a fetched member is not the call's)

    def source(self, value, where: tuple) -> None:
        if isinstance(value, torch.Tensor):
            self.sources.setdefault(id(value), where)
            self.keep.append(value)

    def fail(self, why: str) -> None:
        if self.failed is None:
            self.failed = why[:500]

    # ---- the mode
    def __torch_function__(self, func, types, args=(), kwargs=None):
        kwargs = kwargs or {}
        if self.failed is not None or self.paused:
            return func(*args, **kwargs)
        try:
            name = NAMES.get(func)
        except TypeError:
            name = None
        if name is None:
            self.fail(f"{getattr(func, '__qualname__', func)!s:.100} is not an operation a replay may run")
            return func(*args, **kwargs)
        try:
            enc_args, enc_kwargs = self._value(tuple(args)), self._value(dict(kwargs))
        except Untraceable as exc:
            self.fail(f"{name}: {exc}")
            return func(*args, **kwargs)
        out = func(*args, **kwargs)
        try:
            spec = self._spec(out, len(self.entries))
        except Untraceable as exc:
            self.fail(f"{name} returned {exc}")
            return out
        self.entries.append(["O", name, enc_args, enc_kwargs, spec])
        if len(self.entries) > MAX_ENTRIES:
            self.fail(f"more than {MAX_ENTRIES} operations")
        return out

    # ---- values
    def _tensor(self, t: torch.Tensor):
        ref = self.refs.get(id(t))
        if ref is not None:
            return ref
        where = self.sources.get(id(t))
        if where is not None:  # first use of an env member or argument: a leaf here
            ref = self.refs[id(t)] = ["$r", len(self.entries), None]
            self.entries.append(["L", list(where), str(t.dtype).removeprefix("torch."), list(t.shape)])
            return ref
        self.const_bytes += t.numel() * t.element_size()
        if self.const_bytes > MAX_CONST_BYTES:
            raise Untraceable(f"more than {MAX_CONST_BYTES} bytes of constant tensors")
        self.keep.append(t)
        return ["$c", t.detach().clone()]

    def _value(self, v, depth: int = 0):
        kind = type(v)
        if v is None or kind is bool or kind is int or kind is float:
            return v
        if depth > 16:
            raise Untraceable("a value nested deeper than 16 levels")
        if isinstance(v, torch.Tensor):
            return self._tensor(v)
        if kind is str:
            if len(v) > MAX_STR_CHARS:
                raise Untraceable(f"a string of {len(v)} characters")
            return v
        if kind is torch.Size:
            return ["$z", *[int(d) for d in v]]
        if isinstance(v, list | tuple):
            if len(v) > MAX_SEQUENCE:
                raise Untraceable(f"a sequence of {len(v)} items")
            return ["$l" if kind is list else "$u", *[self._value(x, depth + 1) for x in v]]
        if kind is dict:
            if not all(type(k) is str for k in v):
                raise Untraceable("a dict with keys other than strings")
            return {k: self._value(x, depth + 1) for k, x in v.items()}
        if kind is slice:
            return ["$s", self._value(v.start, depth + 1), self._value(v.stop, depth + 1),
                    self._value(v.step, depth + 1)]
        if v is Ellipsis:
            return ["$e"]
        if isinstance(v, torch.dtype):
            return ["$dt", str(v).removeprefix("torch.")]
        if isinstance(v, torch.device):
            return ["$dev"]
        raise Untraceable(f"a value of type {kind.__name__}")

    def _spec(self, out, index: int):
        if isinstance(out, torch.Tensor):
            self.refs[id(out)] = ["$r", index, None]
            self.keep.append(out)
            return ["T", str(out.dtype).removeprefix("torch."), list(out.shape)]
        if isinstance(out, tuple | list) and out and all(isinstance(x, torch.Tensor) for x in out):
            if len(out) > 64:
                raise Untraceable(f"{len(out)} tensors")
            for j, x in enumerate(out):
                self.refs.setdefault(id(x), ["$r", index, j])  # a split of one tensor may repeat none
                self.keep.append(x)
            self.keep.append(out)
            return ["S", [["T", str(x.dtype).removeprefix("torch."), list(x.shape)] for x in out]]
        if out is None:
            return ["N"]
        if _holds_tensor(out):
            raise Untraceable("tensors mixed with other values")
        return ["V", self._value(out)]  # a Python value the rest of the call may depend on: a guard

    def finish(self, value) -> dict:
        """The graph (``entries`` and the returned ``out``), or ``{"failed": why}``."""
        if self.failed is None:
            try:
                out = self._value(value)
            except Untraceable as exc:
                self.fail(f"the function returned {exc}")
        if self.failed is not None:
            return {"failed": self.failed}
        return {"entries": self.entries, "out": out}
