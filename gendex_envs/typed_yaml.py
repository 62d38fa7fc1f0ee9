"""Strict YAML -> frozen dataclasses, with errors that name the file, the field path, the value and what is allowed.

dacite (strict mode) does the typing; nested dataclasses are built here so an error path carries list indices
(``objects[1].scale``). YAML mappings with duplicate keys are rejected instead of silently keeping the last value.
"""

from __future__ import annotations

import dataclasses
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


def suggest_value(value: str, options: Collection[str]) -> str:
    """Close-name suggestion; exact case-insensitive matches ('rl' -> 'RL') first."""
    same = [o for o in options if o.lower() == str(value).lower()]
    return f" Did you mean: {', '.join(map(repr, same))}?" if same else suggest(str(value), options)


def spec_error(source: str, problems: list[str]) -> TaskSpecError:
    if len(problems) == 1:
        return TaskSpecError(f"invalid task spec {source}: {problems[0]}")
    return TaskSpecError(f"invalid task spec {source} ({len(problems)} problems):\n  - " + "\n  - ".join(problems))


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
    return f"{path} = {value!r} has the wrong type ({type(value).__name__}); expected {type_name(tp)}"


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
    names = [f.name for f in dataclasses.fields(cls)]
    if not isinstance(data, Mapping):
        raise spec_error(source, [f"{where}: expected a mapping with keys {', '.join(names)}; "
                             f"got {data!r} ({type(data).__name__})"])
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
        if dc is not None and not is_seq and isinstance(value, Mapping):
            prepared[name] = build(dc, value, sub, source)
        elif dc is not None and is_seq and value is not None:
            prepared[name] = tuple(build(dc, item, f"{sub}[{i}]", source) for i, item in enumerate(value))
    try:
        return dacite.from_dict(cls, prepared, _DACITE_CONFIG)
    except dacite.UnexpectedDataError as e:
        problems = [f"{where}: unknown key {key!r}.{suggest_value(str(key), names)} Allowed keys: {', '.join(names)}."
                    for key in sorted(e.keys, key=str)]
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
            msg = (f"{full} = {value!r} is not allowed; allowed values: {', '.join(map(repr, allowed))}."
                   f"{suggest_value(str(value), allowed)}")
        elif isinstance(e, dacite.WrongTypeError):
            msg = wrong_type(full, value, tp)
        else:
            msg = f"{full}: {e}"
        raise spec_error(source, [msg]) from None
    except (dacite.DaciteError, TypeError, ValueError) as e:  # pragma: no cover - defensive: one error type out
        raise spec_error(source, [f"{where}: {e}"]) from None


# ---------------------------------------------------------------------------------- semantic checks
