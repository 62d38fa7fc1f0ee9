"""The wire format between the parent and the reward worker: no pickle, in either direction.

A frame is a 12-byte prefix (header length, payload length: little-endian u32 and u64), a JSON header and a payload
of raw tensor bytes. Values are JSON with two tagged forms: ``{"$t": i}`` is the i-th tensor of the header's
``tensors`` list (dtype from :data:`DTYPES`, shape, byte offset into the payload, little-endian, C order) and
``{"$d": [[key, value], ...]}`` a dict with string keys (tuples arrive as lists). The reader checks every bound
(:data:`MAX_HEADER_BYTES`, :data:`MAX_PAYLOAD_BYTES`, :data:`MAX_TENSORS`, :data:`MAX_DEPTH`), every dtype, shape
and offset, before it builds anything; a frame that breaks one raises :class:`ProtocolError`. Stdlib and torch only:
the worker imports this file without the ``gendex_envs`` package.
"""

from __future__ import annotations

import json
import math
import os
import struct
import sys

import torch

MAX_HEADER_BYTES = 1 << 20
"""A call's header holds names, shapes and small numbers: a few KB."""
MAX_PAYLOAD_BYTES = 256 << 20
"""The tensors of one frame (a 4096-env batch of a big observation is a few MB)."""
MAX_TENSORS = 4096
MAX_DEPTH = 16
MAX_NDIM = 8
DTYPES = {name: getattr(torch, name) for name in (
    "float32", "float64", "float16", "bfloat16", "int64", "int32", "int16", "int8", "uint8", "bool")}
"""The only tensor types that cross (no complex, no quantized, no sparse)."""
_NAMES = {dtype: name for name, dtype in DTYPES.items()}
_SIZES = {name: torch.empty((), dtype=dtype).element_size() for name, dtype in DTYPES.items()}
_ALIGN = 8
"""Each tensor starts at a multiple of 8 bytes of the payload, so that it can be read in place."""
_PREFIX = struct.Struct("<IQ")
assert sys.byteorder == "little", "the wire format is little-endian"


class ProtocolError(ValueError):
    """A frame that breaks the format or one of its bounds."""


# ---------------------------------------------------------------------------------------------- encoding
def encode(value, tensors: list, depth: int = 0):
    """``value`` as JSON-ready data; its tensors (moved to the CPU, contiguous) are appended to ``tensors``."""
    kind = type(value)
    if kind is str or kind is int or kind is bool or value is None:
        return value
    if depth > MAX_DEPTH:
        raise ProtocolError(f"value nested deeper than {MAX_DEPTH} levels")
    if isinstance(value, torch.Tensor):
        if value.dtype not in _NAMES:
            raise ProtocolError(f"tensor of dtype {value.dtype}; allowed: {sorted(DTYPES)}")
        if value.device.type != "cpu" or value.requires_grad or not value.is_contiguous():
            value = value.detach().to("cpu").contiguous()
        tensors.append(value)
        return {"$t": len(tensors) - 1}
    if value is None or isinstance(value, bool | int | str):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else {"$f": repr(value)}
    if isinstance(value, dict):
        if not all(isinstance(k, str) for k in value):
            raise ProtocolError("dict keys must be strings")
        return {"$d": [[k, encode(v, tensors, depth + 1)] for k, v in value.items()]}
    if isinstance(value, list | tuple):
        return [encode(v, tensors, depth + 1) for v in value]
    raise ProtocolError(f"a value of type {type(value).__name__} cannot cross the sandbox; allowed: tensors, dicts "
                        f"with string keys, lists, tuples, str, int, float, bool, None")


def frame(header: dict, tensors: list) -> list:
    """The byte strings of one frame (header already holds encoded values; ``tensors`` from :func:`encode`)."""
    specs, chunks, offset = [], [], 0
    for t in tensors:
        name = _NAMES[t.dtype]
        n = t.numel() * _SIZES[name]
        pad = -offset % _ALIGN
        if pad:
            chunks.append(bytes(pad))
            offset += pad
        specs.append([name, list(t.shape), offset])
        if n:
            chunks.append((t.view(torch.int16) if name == "bfloat16" else t).numpy().tobytes())
        offset += n
    header = dict(header, tensors=specs)
    text = json.dumps(header, separators=(",", ":")).encode()
    if len(text) > MAX_HEADER_BYTES or offset > MAX_PAYLOAD_BYTES:
        raise ProtocolError(f"frame of {len(text)} header and {offset} payload bytes; at most {MAX_HEADER_BYTES} and "
                            f"{MAX_PAYLOAD_BYTES}")
    return [_PREFIX.pack(len(text), offset), text, *chunks]


def write_frame(fd: int, header: dict, tensors: list) -> None:
    data = b"".join(frame(header, tensors))
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]


# ---------------------------------------------------------------------------------------------- decoding
def read_exact(fd: int, n: int, wait=None) -> bytearray:
    """``n`` bytes from ``fd``; ``wait()`` (if given) is called before each read and may raise (a deadline)."""
    buf = bytearray(n)
    view, got = memoryview(buf), 0
    while got < n:
        if wait is not None:
            wait()
        k = os.readv(fd, [view[got:]])
        if k == 0:
            raise EOFError(f"the other side closed the channel ({got} of {n} bytes read)")
        got += k
    return buf


def read_frame(fd: int, wait=None, device=None) -> dict:
    """One frame's header with its values decoded (tensors on ``device``); raises :class:`ProtocolError`."""
    head_len, payload_len = _PREFIX.unpack(read_exact(fd, _PREFIX.size, wait))
    if head_len > MAX_HEADER_BYTES or payload_len > MAX_PAYLOAD_BYTES:
        raise ProtocolError(f"frame announces {head_len} header and {payload_len} payload bytes; at most "
                            f"{MAX_HEADER_BYTES} and {MAX_PAYLOAD_BYTES}")
    try:
        header = json.loads(bytes(read_exact(fd, head_len, wait)))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise ProtocolError(f"frame header is not JSON: {exc}") from None
    payload = read_exact(fd, payload_len, wait) if payload_len else bytearray()
    if not isinstance(header, dict) or not isinstance(header.get("tensors", []), list):
        raise ProtocolError("frame header is not an object with a tensor list")
    tensors = _tensors(header.pop("tensors", []), payload, device)
    return {k: _decode(v, tensors, 0) for k, v in header.items()}


def _tensors(specs: list, payload: bytearray, device) -> list:
    if len(specs) > MAX_TENSORS:
        raise ProtocolError(f"{len(specs)} tensors in a frame; at most {MAX_TENSORS}")
    out, end = [], 0
    for spec in specs:
        if not (isinstance(spec, list) and len(spec) == 3 and spec[0] in DTYPES and isinstance(spec[1], list)
                and len(spec[1]) <= MAX_NDIM and all(type(d) is int and 0 <= d <= MAX_PAYLOAD_BYTES for d in spec[1])
                and type(spec[2]) is int):
            raise ProtocolError(f"bad tensor description {str(spec)[:200]}; expected [dtype, shape, offset] with "
                                f"dtype in {sorted(DTYPES)}")
        dtype, shape, offset = DTYPES[spec[0]], spec[1], spec[2]
        count = math.prod(shape)
        n = count * _SIZES[spec[0]]
        if offset != end + (-end % _ALIGN) or offset + n > len(payload):
            raise ProtocolError(f"tensor bytes {offset}..{offset + n} outside the payload of {len(payload)} bytes")
        end = offset + n
        t = (torch.frombuffer(payload, dtype=dtype, count=count, offset=offset).view(shape)
             if n else torch.empty(shape, dtype=dtype))
        out.append(t if device is None or torch.device(device).type == "cpu" else t.to(device))
    if end != len(payload):
        raise ProtocolError(f"{len(payload) - end} payload bytes belong to no tensor")
    return out


_SCALARS = frozenset({str, int, float, bool, type(None)})


def _decode(value, tensors: list, depth: int):
    kind = type(value)
    if kind in _SCALARS:
        return value
    if depth > MAX_DEPTH:
        raise ProtocolError(f"value nested deeper than {MAX_DEPTH} levels")
    if kind is list:
        return [v if type(v) in _SCALARS else _decode(v, tensors, depth + 1) for v in value]
    if kind is dict:
        if len(value) == 1 and "$t" in value:
            i = value["$t"]
            if type(i) is not int or not 0 <= i < len(tensors):
                raise ProtocolError(f"tensor reference {str(i)[:50]} out of range")
            return tensors[i]
        if len(value) == 1 and "$f" in value and value["$f"] in ("nan", "inf", "-inf"):
            return float(value["$f"])
        if len(value) == 1 and isinstance(value.get("$d"), list):
            out = {}
            for item in value["$d"]:
                if not (type(item) is list and len(item) == 2 and type(item[0]) is str):
                    raise ProtocolError("bad dict entry")
                out[item[0]] = _decode(item[1], tensors, depth + 1)
            return out
        raise ProtocolError(f"untagged object {str(value)[:100]}")
    raise ProtocolError(f"unexpected value {str(value)[:100]}")
