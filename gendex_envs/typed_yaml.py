"""Strict YAML -> frozen dataclasses, with errors that name the file, the field path, the value and what is allowed.

dacite (strict mode) does the typing; nested dataclasses are built here so an error path carries list indices
(``objects[1].scale``). YAML mappings with duplicate keys are rejected instead of silently keeping the last value.

Task files, language-model replies and transcripts are untrusted input (shared, downloaded, written by a model), so
every one of them is read by :func:`load_yaml_bounded` / :func:`load_json_bounded`: size refused before parsing,
no anchors, aliases, merge keys or non-core tags, nesting depth, node count, string length and integer size capped
while composing. The limits are the ``MAX_*`` constants below (``docs/security.md`` says why each one is what it is),
and an error message quotes at most :data:`QUOTE_CHARS` characters of any value (:func:`quote`).
"""

from __future__ import annotations

import dataclasses
import json
import reprlib
import types
from collections.abc import Collection, Mapping
from typing import Any, Literal, Union, get_args, get_origin, get_type_hints

import dacite
import yaml

from gendex_envs.errors import TaskSpecError, suggest


def _number_hook(tp: type) -> Any:
    """dacite hook: reject bools (an int subclass: YAML `true` must not become 1), widen ints for float fields."""
    def hook(value: Any) -> Any:
        if isinstance(value, bool):
            raise dacite.WrongTypeError(field_type=tp, value=value)
        return float(value) if tp is float and isinstance(value, int) else value
    return hook


_DACITE_CONFIG = dacite.Config(strict=True, cast=[tuple],
                               type_hooks={float: _number_hook(float), int: _number_hook(int)})


class UniqueKeyLoader(yaml.SafeLoader):
    """SafeLoader that rejects duplicate mapping keys instead of silently keeping the last one."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        seen: set = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if isinstance(key, str):
                if key in seen:
                    raise yaml.constructor.ConstructorError(None, None, f"duplicate key {key!r}", key_node.start_mark)
                seen.add(key)
        return super().construct_mapping(node, deep=deep)


# ------------------------------------------------------------------------------- bounds on untrusted input
MAX_INPUT_BYTES = 1_000_000
"""Largest task file or model reply (bytes, UTF-8), refused before parsing; a real task file is about 3 KB."""
MAX_DEPTH = 32
"""Deepest nesting of mappings and lists; a task file nests 6 deep. Also keeps the recursive composer in bounds."""
MAX_NODES = 20_000
"""Most YAML/JSON nodes (scalars, lists, mappings) in one document; 64 objects with 32 stages need about 5 000."""
MAX_STRING_CHARS = 4096
"""Longest scalar (a name, an instruction, a description) in characters."""
MAX_INT_BITS = 63
"""Integers must fit a signed 64-bit int (|n| < 2**63): a 4000-digit integer overflows a float field."""
QUOTE_CHARS = 200
"""Most characters of a value quoted in an error message (:func:`quote`)."""
MAX_PROBLEMS = 20
"""Most problems listed in one TaskSpecError (the count of the rest is given)."""

MAX_OBJECTS = 64
"""Objects in a task: each object's meshes take SAPIEN materials, and past its 64K-material limit SAPIEN segfaults
instead of raising; 64 is far above any task's need (the library's largest has 6)."""
MAX_STAGES = 32
"""Stages of a task (the library's longest has 8)."""
MAX_CONDITIONS = 32
"""Success conditions of the task or of one stage."""
MAX_JOINT_STATES = 64
"""Entries of one object's ``joint_state``."""
MAX_STEPS = 100_000
"""Ceiling on ``max_episode_steps``, a stage's ``horizon`` and ``hold_steps``: buffers are sized from them."""
MAX_POSITION_M = 20.0
"""Bound (m) on every position coordinate and length of a spec: objects' ``pos_m``, ``goal.pos_m``,
``robot.base_pos_m``, the goal's radius and the conditions' distances. A finite but absurd value (1e30) would go into
PhysX as a pose. The committed library's largest is 0.8 m (the table is 1.6 m x 1.2 m); the asset tests lay every
articulated model out on one grid, 5.2 m across, and larger catalogs will need more."""

MAX_TRANSCRIPT_BYTES = 256_000_000
"""Largest transcript (JSONL) read for replay; recorded runs are about 0.5 MB."""
MAX_TRANSCRIPT_LINE_BYTES = 8_000_000
"""Longest transcript line (one exchange: prompt, context and reply)."""
MAX_TRANSCRIPT_EXCHANGES = 10_000
"""Most exchanges in one transcript; a generation run makes a few dozen."""

_CORE_TAGS = frozenset("tag:yaml.org,2002:" + t for t in ("str", "int", "float", "bool", "null", "seq", "map"))

_REPR = reprlib.Repr()
_REPR.maxstring = _REPR.maxother = _REPR.maxlong = QUOTE_CHARS
_REPR.maxlist = _REPR.maxtuple = _REPR.maxdict = _REPR.maxset = 8
_REPR.maxlevel = 3


def quote(value: Any, limit: int = QUOTE_CHARS) -> str:
    """``repr(value)`` cut to at most ``limit`` characters (plus a note of the full length of a long string), so an
    error message never carries a huge value; the full repr is never built for containers."""
    text = _REPR.repr(value)
    if len(text) > limit:
        text = text[:limit] + "..."
    if isinstance(value, (str, bytes)) and len(value) > limit:
        text += f" ({len(value)} characters)"
    return text


def clip(text: str, limit: int = 4 * QUOTE_CHARS) -> str:
    """``text`` cut to ``limit`` characters (for messages of third-party errors that may embed a value)."""
    return text if len(text) <= limit else text[:limit] + f"... ({len(text)} characters)"


class InputBoundsError(yaml.MarkedYAMLError, ValueError):
    """Untrusted YAML/JSON exceeds a bound (size, depth, nodes, string length) or uses a refused construct
    (anchors, aliases, merge keys, tags). A YAMLError (callers report it as they report bad YAML) and a ValueError
    (as json.JSONDecodeError is)."""

    def __init__(self, problem: str, mark: Any = None) -> None:
        super().__init__(problem=problem, problem_mark=mark)


def _check_size(data: str | bytes, source: str, max_bytes: int) -> str:
    """The text of ``data``, refused (InputBoundsError) when larger than ``max_bytes`` or not UTF-8."""
    if isinstance(data, str):
        # a str of more than max_bytes characters is surely too big; else count its UTF-8 bytes
        size = len(data) if len(data) > max_bytes else len(data.encode("utf-8", "surrogatepass"))
    else:
        size = len(data)
    if size > max_bytes:
        raise InputBoundsError(f"{source} is {size} bytes; at most {max_bytes} bytes are allowed (refused before "
                               "parsing)")
    if isinstance(data, bytes):
        try:
            data = data.decode("utf-8")
        except UnicodeDecodeError as e:
            raise InputBoundsError(f"{source} is not UTF-8 text: byte {quote(e.object[e.start:e.start + 1])} at "
                                   f"offset {e.start}") from None
    return data


class BoundedLoader(UniqueKeyLoader):
    """UniqueKeyLoader for untrusted text. While composing, before any object is built, it refuses merge keys
    (``<<``), tags other than the core ones (str, int, float, bool, null, seq, map), scalars longer than
    MAX_STRING_CHARS, and documents with more than MAX_NODES nodes or nesting deeper than MAX_DEPTH *counting every
    alias as the whole subtree it stands for*: an alias bomb (billion laughs) is refused after a few hundred events
    instead of expanding. A recursive alias (a node that contains itself) is refused. Plain anchors and aliases stay
    legal: committed task files use them for a condition repeated between a stage and the task. Integers must fit
    MAX_INT_BITS; timestamps stay strings."""

    def __init__(self, stream: Any) -> None:
        super().__init__(stream)
        self._depth = 0
        self._nodes = 0
        self._size: dict[int, tuple[int, int]] = {}  # id(node) -> (nodes, height), aliases expanded

    def _count(self, nodes: int, mark: Any) -> None:
        self._nodes += nodes
        if self._nodes > MAX_NODES:
            raise InputBoundsError(f"more than {MAX_NODES} nodes (values, lists, mappings; an alias counts as all "
                                   f"the nodes it stands for); at most {MAX_NODES} are allowed", mark)

    def _too_deep(self, mark: Any) -> InputBoundsError:
        return InputBoundsError(f"nesting deeper than {MAX_DEPTH} levels (aliases expanded); at most {MAX_DEPTH} are "
                                "allowed", mark)

    def compose_node(self, parent: Any, index: Any) -> Any:
        event = self.peek_event()
        if isinstance(event, yaml.AliasEvent):
            target = self.anchors.get(event.anchor)
            if target is not None:
                if id(target) not in self._size:
                    raise InputBoundsError(f"recursive alias *{quote(event.anchor, 40)[1:-1]} (a node that contains "
                                           "itself) is not allowed", event.start_mark)
                nodes, height = self._size[id(target)]
                self._count(nodes, event.start_mark)
                if self._depth + height > MAX_DEPTH:
                    raise self._too_deep(event.start_mark)
            return super().compose_node(parent, index)  # undefined alias: the composer's own error
        tag = getattr(event, "tag", None)
        if tag not in (None, "!") and tag not in _CORE_TAGS:
            raise InputBoundsError(f"tag {quote(tag)} is not allowed; only plain values, lists and mappings",
                                   event.start_mark)
        self._count(1, event.start_mark)
        if isinstance(event, yaml.ScalarEvent) and len(event.value) > MAX_STRING_CHARS:
            raise InputBoundsError(f"a value of {len(event.value)} characters; at most {MAX_STRING_CHARS} are "
                                   "allowed", event.start_mark)
        if self._depth >= MAX_DEPTH:
            raise self._too_deep(event.start_mark)
        self._depth += 1
        try:
            node = super().compose_node(parent, index)
        finally:
            self._depth -= 1
        if isinstance(node, yaml.ScalarNode):
            self._size[id(node)] = (1, 1)
        else:
            children = [c for pair in node.value for c in pair] if isinstance(node, yaml.MappingNode) else node.value
            sizes = [self._size[id(c)] for c in children]
            self._size[id(node)] = (1 + sum(n for n, _ in sizes), 1 + max((h for _, h in sizes), default=0))
        return node

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                raise InputBoundsError("merge keys (<<) are not allowed; write the keys out", key_node.start_mark)
        return super().construct_mapping(node, deep=deep)

    def construct_bounded_int(self, node: yaml.ScalarNode) -> int:
        value = self.construct_yaml_int(node)
        if abs(value) >= 2 ** MAX_INT_BITS:
            raise InputBoundsError(f"integer {quote(node.value, 60)} is out of range; integers must lie within "
                                   f"+/-2**{MAX_INT_BITS}", node.start_mark)
        return value

    def construct_bounded_float(self, node: yaml.ScalarNode) -> float:
        try:
            return self.construct_yaml_float(node)
        except (OverflowError, ValueError):  # sexagesimal 1:2:...:3.5 with hundreds of parts
            raise InputBoundsError(f"number {quote(node.value, 60)} is out of range", node.start_mark) from None


BoundedLoader.add_constructor("tag:yaml.org,2002:int", BoundedLoader.construct_bounded_int)
BoundedLoader.add_constructor("tag:yaml.org,2002:float", BoundedLoader.construct_bounded_float)
BoundedLoader.add_constructor("tag:yaml.org,2002:timestamp", BoundedLoader.construct_yaml_str)


def parse_yaml_bounded(data: str | bytes, source: str = "<text>", max_bytes: int = MAX_INPUT_BYTES) -> Any:
    """Parse one untrusted YAML document with :class:`BoundedLoader`; every failure is a ``yaml.YAMLError``
    (:class:`InputBoundsError` for a broken bound) carrying, where known, the line and column."""
    text = _check_size(data, source, max_bytes)
    try:
        return yaml.load(text, Loader=BoundedLoader)  # a SafeLoader subclass
    except yaml.YAMLError:
        raise
    except (RecursionError, OverflowError, ValueError, TypeError) as e:  # defensive: the loader's own bugs
        raise InputBoundsError(f"cannot parse: {clip(str(e))}") from None


def yaml_error_text(err: yaml.YAMLError) -> tuple[str, str]:
    """(where, what) of a YAML error: ``", line L, column C"`` (or '') and the problem, clipped."""
    mark = getattr(err, "problem_mark", None)
    where = f", line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
    what = " ".join(x for x in (getattr(err, "context", None), getattr(err, "problem", None)) if x) or str(err)
    return where, clip(what)


def load_yaml_bounded(data: str | bytes, source: str, error: type[Exception] = TaskSpecError,
                      max_bytes: int = MAX_INPUT_BYTES) -> Any:
    """:func:`parse_yaml_bounded`, any failure raised as ``error("invalid YAML in {source}, line L, column C:
    {problem}")``."""
    try:
        return parse_yaml_bounded(data, source, max_bytes)
    except yaml.YAMLError as e:
        where, what = yaml_error_text(e)
        raise error(f"invalid YAML in {source}{where}: {what}") from None


def _json_unique(pairs: list[tuple[str, Any]]) -> dict:
    out: dict = {}
    for key, value in pairs:
        if key in out:
            raise InputBoundsError(f"duplicate key {quote(key)}")
        out[key] = value
    return out


def _json_int(text: str) -> int:
    value = int(text) if len(text) <= 40 else 2 ** MAX_INT_BITS
    if abs(value) >= 2 ** MAX_INT_BITS:
        raise InputBoundsError(f"integer {quote(text, 60)} is out of range; integers must lie within "
                               f"+/-2**{MAX_INT_BITS}")
    return value


def check_tree(value: Any, max_depth: int = MAX_DEPTH, max_nodes: int = MAX_NODES,
               max_string: int | None = MAX_STRING_CHARS) -> None:
    """Refuse (InputBoundsError) an already-parsed tree deeper than ``max_depth``, with more than ``max_nodes``
    nodes or (unless ``max_string`` is None) a string longer than ``max_string``; iterative, stops at the first."""
    stack: list[tuple[Any, int]] = [(value, 1)]
    nodes = 0
    while stack:
        item, depth = stack.pop()
        nodes += 1
        if nodes > max_nodes:
            raise InputBoundsError(f"more than {max_nodes} nodes (values, lists, mappings); at most {max_nodes} are "
                                   "allowed")
        if isinstance(item, (dict, list)):
            if depth > max_depth:
                raise InputBoundsError(f"nesting deeper than {max_depth} levels; at most {max_depth} are allowed")
            children = list(item.keys()) + list(item.values()) if isinstance(item, dict) else item
            stack.extend((c, depth + 1) for c in children)
        elif isinstance(item, str) and max_string is not None and len(item) > max_string:
            raise InputBoundsError(f"a value of {len(item)} characters; at most {max_string} are allowed")


def parse_json_bounded(data: str | bytes, source: str = "<text>", max_bytes: int = MAX_INPUT_BYTES,
                       max_string: int | None = MAX_STRING_CHARS, max_nodes: int = MAX_NODES,
                       finite: bool = True) -> Any:
    """Parse untrusted JSON: size refused before parsing, duplicate keys, NaN/Infinity (if ``finite``) and integers
    beyond MAX_INT_BITS refused, then depth, node count and string length checked (:func:`check_tree`). Every failure
    is a ``ValueError``: ``json.JSONDecodeError`` or :class:`InputBoundsError`."""
    text = _check_size(data, source, max_bytes)

    def no_constant(name: str) -> Any:
        raise InputBoundsError(f"{name} is not allowed; numbers must be finite")

    try:
        value = json.loads(text, object_pairs_hook=_json_unique, parse_int=_json_int,
                           parse_constant=no_constant if finite else None)
    except RecursionError:
        raise InputBoundsError(f"nesting deeper than {MAX_DEPTH} levels; at most {MAX_DEPTH} are allowed") from None
    check_tree(value, max_nodes=max_nodes, max_string=max_string)
    return value


def suggest_value(value: str, options: Collection[str]) -> str:
    """Close-name suggestion; exact case-insensitive matches ('rl' -> 'RL') first."""
    same = [o for o in options if o.lower() == str(value).lower()]
    return f" Did you mean: {', '.join(map(repr, same))}?" if same else suggest(str(value), options)


def spec_error(source: str, problems: list[str]) -> TaskSpecError:
    """One TaskSpecError listing ``problems`` (at most MAX_PROBLEMS of them, each clipped)."""
    problems = [clip(p) for p in problems]
    if len(problems) == 1:
        return TaskSpecError(f"invalid task spec {source}: {problems[0]}")
    shown = problems[:MAX_PROBLEMS]
    more = f"\n  - ... and {len(problems) - len(shown)} more" if len(problems) > len(shown) else ""
    return TaskSpecError(f"invalid task spec {source} ({len(problems)} problems):\n  - " + "\n  - ".join(shown)
                         + more)


def bounded_field(limit: int, items: str, why: str, **kwargs: Any) -> Any:
    """A dataclass field whose list or mapping may hold at most ``limit`` entries, checked (by :func:`build`) before
    any entry is built; ``items`` names them and ``why`` names the bound in the error."""
    return dataclasses.field(metadata={"max_items": limit, "items": items, "why": why}, **kwargs)


def join_path(path: str, name: str) -> str:
    return f"{path}.{name}" if path else name


def _is_union(tp: Any) -> bool:
    return get_origin(tp) in (Union, types.UnionType)


def type_name(tp: Any) -> str:
    simple = {float: "a number", int: "an integer", str: "a string", bool: "a boolean (true/false)",
              type(None): "null"}
    if tp in simple:
        return simple[tp]
    origin, args = get_origin(tp), get_args(tp)
    if origin is Literal:
        return "one of " + ", ".join(repr(a) for a in args)
    if _is_union(tp):
        return " or ".join(type_name(a) for a in args)
    if origin is tuple and len(args) == 2 and args[1] is Ellipsis:
        item = f"mappings ({args[0].__name__})" if dataclasses.is_dataclass(args[0]) else type_name(args[0])
        return f"a list of {item}"
    if origin is tuple:
        kinds = {type_name(a) for a in args}
        return f"a list of {len(args)} numbers" if kinds == {"a number"} else f"a list of {len(args)} items"
    if origin is dict:
        return f"a mapping from {type_name(args[0])} to {type_name(args[1])}"
    if dataclasses.is_dataclass(tp):
        return f"a mapping ({tp.__name__})"
    return str(tp)


def wrong_type(path: str, value: Any, tp: Any) -> str:
    return f"{path} = {quote(value)} has the wrong type ({type(value).__name__}); expected {type_name(tp)}"


def _strip_none(tp: Any) -> Any:
    """X for X | None, else tp unchanged."""
    args = [a for a in get_args(tp) if a is not type(None)]
    return args[0] if _is_union(tp) and len(args) == 1 else tp


def _nested_dataclass(tp: Any) -> tuple[type | None, bool]:
    """(dataclass, is_sequence) for fields typed DC, DC | None or tuple[DC, ...]; (None, False) otherwise."""
    tp = _strip_none(tp)
    args = get_args(tp)
    if dataclasses.is_dataclass(tp):
        return tp, False
    if get_origin(tp) is tuple and len(args) == 2 and args[1] is Ellipsis and dataclasses.is_dataclass(args[0]):
        return args[0], True
    return None, False


def build(cls: type, data: Any, path: str, source: str) -> Any:
    """Build ``cls`` from ``data`` with dacite; nested dataclasses are built here so paths carry list indices."""
    where = path or "top level"
    fields = {f.name: f for f in dataclasses.fields(cls)}
    names = list(fields)
    if not isinstance(data, Mapping):
        raise spec_error(source, [f"{where}: expected a mapping with keys {', '.join(names)}; "
                             f"got {quote(data)} ({type(data).__name__})"])
    hints = get_type_hints(cls)
    prepared = dict(data)
    for name in names:
        if name not in data:
            continue
        sub, value = join_path(path, name), data[name]
        dc, is_seq = _nested_dataclass(hints[name])
        bare = _strip_none(hints[name])
        container = {tuple: (list, tuple), dict: Mapping}.get(get_origin(bare))
        if container and not isinstance(value, container) and not (value is None and bare is not hints[name]):
            raise spec_error(source, [wrong_type(sub, value, hints[name])])  # dacite's tuple cast would crash/split
        limit = fields[name].metadata.get("max_items")
        if limit is not None and container and isinstance(value, Collection) and len(value) > limit:
            raise spec_error(source, [f"{sub}: {len(value)} {fields[name].metadata.get('items', 'items')}; at most "
                                      f"{limit} are allowed ({fields[name].metadata.get('why', 'a safety bound')})"])
        if dc is not None and not is_seq and isinstance(value, Mapping):
            prepared[name] = build(dc, value, sub, source)
        elif dc is not None and is_seq and value is not None:
            prepared[name] = tuple(build(dc, item, f"{sub}[{i}]", source) for i, item in enumerate(value))
    try:
        return dacite.from_dict(cls, prepared, _DACITE_CONFIG)
    except dacite.UnexpectedDataError as e:
        problems = [f"{where}: unknown key {quote(key)}.{suggest_value(str(key)[:QUOTE_CHARS], names)} Allowed keys: "
                    f"{', '.join(names)}." for key in sorted(e.keys, key=str)]
        raise spec_error(source, problems) from None
    except dacite.MissingValueError as e:
        name = (e.field_path or "").split(".")[0]
        expected = type_name(hints[name]) if name in hints else "a value"
        raise spec_error(source, [f"{join_path(path, e.field_path or '')}: required field is missing "
                             f"(expected {expected})"]) from None
    except dacite.DaciteFieldError as e:
        name = (e.field_path or "").split(".")[0]
        full, tp = join_path(path, name), hints.get(name)
        value = data.get(name, getattr(e, "value", None))
        if get_origin(_strip_none(tp)) is Literal and isinstance(value, str):
            allowed = [str(a) for a in get_args(_strip_none(tp))]
            msg = (f"{full} = {quote(value)} is not allowed; allowed values: {', '.join(map(repr, allowed))}."
                   f"{suggest_value(value[:QUOTE_CHARS], allowed)}")
        elif isinstance(e, dacite.WrongTypeError):
            msg = wrong_type(full, value, tp)
        else:
            msg = f"{full}: {clip(str(e))}"
        raise spec_error(source, [msg]) from None
    except (dacite.DaciteError, TypeError, ValueError) as e:  # pragma: no cover - defensive: one error type out
        raise spec_error(source, [f"{where}: {clip(str(e))}"]) from None


# ---------------------------------------------------------------------------------- semantic checks
