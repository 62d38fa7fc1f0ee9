"""Typed schema of a task YAML file (``generated_tasks/<Name>/v<N>/task.yaml``).

A task file is loaded with dacite in strict mode into the frozen dataclasses below, then checked
semantically (ranges, name patterns, cross references). Every problem is reported as one
:class:`~gendex_envs.errors.TaskSpecError` naming the file, the field path (``objects[1].scale``),
the bad value and what is allowed. Lengths are in metres, angles in degrees. The table top is the
world plane z = 0. See ``docs/task_spec.md`` for the field reference and a full example.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import re
import types
from collections.abc import Collection, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, Union, get_args, get_origin, get_type_hints

import dacite
import yaml

from gendex_envs.errors import TaskSpecError, suggest

log = logging.getLogger(__name__)

RobotUid = Literal["ur10e_shadow"]
Keyframe = Literal["rest", "pregrasp_open", "palm_up"]
StageMethod = Literal["motion_planning", "RL"]
ControlJoint = Literal["arm", "hand", "both", "three_finger", "arm_two_finger", "lift_inspire"]
ConditionType = Literal["lifted", "inside", "joint_open", "near"]

ROBOT_UIDS: tuple[str, ...] = get_args(RobotUid)
KEYFRAMES: tuple[str, ...] = get_args(Keyframe)
STAGE_METHODS: tuple[str, ...] = get_args(StageMethod)
CONTROL_JOINT_MODES: tuple[str, ...] = get_args(ControlJoint)
CONDITION_TYPES: tuple[str, ...] = get_args(ConditionType)

SCALE_RANGE: tuple[float, float] = (0.3, 2.0)
QUAT_NORM_TOL = 1e-3
GOAL_TARGET = "goal"
"""Reserved name: a ``near`` condition with ``target: goal`` refers to the task's goal site."""
TASK_NAME_RE = re.compile(r"^[A-Z][A-Za-z0-9]*$")
SNAKE_NAME_RE = re.compile(r"^[a-z][a-z0-9_]*$")


@dataclass(frozen=True, kw_only=True)
class TableSpec:
    """The table; its top is the world plane z = 0."""

    size_m: tuple[float, float] = (1.6, 1.2)
    """Table top extent along x and y (m), both > 0."""
    height_m: float = 0.76
    """Height of the table top above the floor (m), > 0."""
    friction: float = 0.8
    """Friction coefficient of the table top, > 0."""


@dataclass(frozen=True, kw_only=True)
class RobotSpec:
    """The robot and where it stands."""

    uid: RobotUid = "ur10e_shadow"
    """Robot id; one of ROBOT_UIDS."""
    base_pos_m: tuple[float, float, float] = (-0.8, 0.0, 0.0)
    """World position of the arm base (m)."""
    base_yaw_deg: float = 0.0
    """Rotation of the arm base about world z (degrees)."""
    init_keyframe: Keyframe = "rest"
    """Initial joint configuration; one of KEYFRAMES."""


@dataclass(frozen=True, kw_only=True)
class RandomizeSpec:
    """Half-ranges of uniform noise added to an object's initial pose at every reset."""

    xy_m: tuple[float, float] = (0.0, 0.0)
    """Half-range of x and y noise (m), each >= 0."""
    yaw_deg: float = 0.0
    """Half-range of yaw noise about world z (degrees), >= 0."""


@dataclass(frozen=True, kw_only=True)
class ObjectSpec:
    """One object placed in the scene."""

    name: str
    """Identifier used by reward code, matching ^[a-z][a-z0-9_]*$; unique within the task."""
    asset: str
    """Asset id from the catalog (``gendex assets`` lists them)."""
    scale: float = 1.0
    """Uniform scale, within SCALE_RANGE."""
    pos_m: tuple[float, float, float]
    """x, y of the object's origin in the world; z = clearance of its lowest point above the table (>= 0)."""
    quat_wxyz: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    """Orientation quaternion (w, x, y, z); its norm must be within QUAT_NORM_TOL of 1 (not normalised)."""
    fixed: bool = False
    """True for objects that never move (e.g. a cabinet body)."""
    joint_state: dict[str, float] = field(default_factory=dict)
    """Initial joint positions by joint name, for articulated assets only."""
    randomize: RandomizeSpec = field(default_factory=RandomizeSpec)
    """Pose noise applied at reset."""
    color_rgba: tuple[float, float, float, float] | None = None
    """Optional colour override, each channel in [0, 1]."""


@dataclass(frozen=True, kw_only=True)
class GoalSpec:
    """An optional goal site shown in the scene."""

    pos_m: tuple[float, float, float]
    """World position of the goal (m); z measured from the table top."""
    radius_m: float = 0.05
    """Radius of the goal sphere (m), > 0."""


@dataclass(frozen=True, kw_only=True)
class StageSpec:
    """One stage of the task, solved by motion planning or RL."""

    name: str
    """Stage identifier, snake_case (^[a-z][a-z0-9_]*$); unique within the task."""
    instruction: str
    """Non-empty natural-language description of the stage."""
    method: StageMethod
    """Solver; one of STAGE_METHODS."""
    control_joint: ControlJoint
    """Which joints the stage controls; one of CONTROL_JOINT_MODES."""
    horizon: int = 100
    """Number of control steps of the stage, >= 1."""
    target: str | None = None
    """Optional name of the object the stage acts on."""


@dataclass(frozen=True, kw_only=True)
class ConditionSpec:
    """One success condition; which fields are used depends on ``type``."""

    type: ConditionType
    """Condition kind; one of CONDITION_TYPES."""
    object: str
    """Name of the object the condition is about."""
    target: str | None = None
    """inside: container object name (required); near: object name or 'goal' (required)."""
    min_height_m: float | None = None
    """lifted: required clearance above the table (m), > 0."""
    min_fraction: float | None = None
    """joint_open: required opening as a fraction of the joint range, in (0, 1]."""
    joint: str | None = None
    """joint_open: optional joint name (default: the asset's main joint)."""
    max_dist_m: float | None = None
    """near: required maximum distance between object and target (m), > 0."""


@dataclass(frozen=True, kw_only=True)
class SuccessSpec:
    """When the task counts as solved."""

    description: str
    """Non-empty natural-language description of success."""
    conditions: tuple[ConditionSpec, ...]
    """At least one condition; all must hold."""
    hold_steps: int = 0
    """Number of consecutive steps the conditions must hold, >= 0."""


@dataclass(frozen=True, kw_only=True)
class TaskSpec:
    """A whole task file."""

    name: str
    """CamelCase task identifier (^[A-Z][A-Za-z0-9]*$)."""
    instruction: str
    """Non-empty natural-language task instruction."""
    table: TableSpec = field(default_factory=TableSpec)
    """The table."""
    robot: RobotSpec = field(default_factory=RobotSpec)
    """The robot."""
    objects: tuple[ObjectSpec, ...]
    """Objects in the scene, at least one; names unique."""
    goal: GoalSpec | None = None
    """Optional goal site."""
    stages: tuple[StageSpec, ...]
    """Stages in execution order, at least one."""
    success: SuccessSpec
    """Success criterion."""
    max_episode_steps: int = 200
    """Episode length limit in control steps, >= 1."""

    def object(self, name: str) -> ObjectSpec:
        """Return the object called ``name``; TaskSpecError (with suggestions) if there is none."""
        for obj in self.objects:
            if obj.name == name:
                return obj
        names = [o.name for o in self.objects]
        raise TaskSpecError(f"task {self.name!r} has no object {name!r}; objects: {', '.join(names)}."
                            f"{_suggest(name, names)}")


# ----------------------------------------------------------------------------------------- loading
def _number_hook(tp: type) -> Any:
    """dacite hook: reject bools (an int subclass: YAML `true` must not become 1), widen ints for float fields."""
    def hook(value: Any) -> Any:
        if isinstance(value, bool):
            raise dacite.WrongTypeError(field_type=tp, value=value)
        return float(value) if tp is float and isinstance(value, int) else value
    return hook


_DACITE_CONFIG = dacite.Config(strict=True, cast=[tuple],
                               type_hooks={float: _number_hook(float), int: _number_hook(int)})


class _UniqueKeyLoader(yaml.SafeLoader):
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


def _suggest(value: str, options: Collection[str]) -> str:
    """Close-name suggestion; exact case-insensitive matches ('rl' -> 'RL') first."""
    same = [o for o in options if o.lower() == str(value).lower()]
    return f" Did you mean: {', '.join(map(repr, same))}?" if same else suggest(str(value), options)


def _fail(source: str, problems: list[str]) -> TaskSpecError:
    if len(problems) == 1:
        return TaskSpecError(f"invalid task spec {source}: {problems[0]}")
    return TaskSpecError(f"invalid task spec {source} ({len(problems)} problems):\n  - " + "\n  - ".join(problems))


def _join(path: str, name: str) -> str:
    return f"{path}.{name}" if path else name


def _is_union(tp: Any) -> bool:
    return get_origin(tp) in (Union, types.UnionType)


def _type_name(tp: Any) -> str:
    simple = {float: "a number", int: "an integer", str: "a string", bool: "a boolean (true/false)",
              type(None): "null"}
    if tp in simple:
        return simple[tp]
    origin, args = get_origin(tp), get_args(tp)
    if origin is Literal:
        return "one of " + ", ".join(repr(a) for a in args)
    if _is_union(tp):
        return " or ".join(_type_name(a) for a in args)
    if origin is tuple and len(args) == 2 and args[1] is Ellipsis:
        item = f"mappings ({args[0].__name__})" if dataclasses.is_dataclass(args[0]) else _type_name(args[0])
        return f"a list of {item}"
    if origin is tuple:
        kinds = {_type_name(a) for a in args}
        return f"a list of {len(args)} numbers" if kinds == {"a number"} else f"a list of {len(args)} items"
    if origin is dict:
        return f"a mapping from {_type_name(args[0])} to {_type_name(args[1])}"
    if dataclasses.is_dataclass(tp):
        return f"a mapping ({tp.__name__})"
    return str(tp)


def _wrong_type(path: str, value: Any, tp: Any) -> str:
    return f"{path} = {value!r} has the wrong type ({type(value).__name__}); expected {_type_name(tp)}"


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


def _build(cls: type, data: Any, path: str, source: str) -> Any:
    """Build ``cls`` from ``data`` with dacite; nested dataclasses are built here so paths carry list indices."""
    where = path or "top level"
    names = [f.name for f in dataclasses.fields(cls)]
    if not isinstance(data, Mapping):
        raise _fail(source, [f"{where}: expected a mapping with keys {', '.join(names)}; "
                             f"got {data!r} ({type(data).__name__})"])
    hints = get_type_hints(cls)
    prepared = dict(data)
    for name in names:
        if name not in data:
            continue
        sub, value = _join(path, name), data[name]
        dc, is_seq = _nested_dataclass(hints[name])
        bare = _strip_none(hints[name])
        container = {tuple: (list, tuple), dict: Mapping}.get(get_origin(bare))
        if container and not isinstance(value, container) and not (value is None and bare is not hints[name]):
            raise _fail(source, [_wrong_type(sub, value, hints[name])])  # dacite's tuple cast would crash/split
        if dc is not None and not is_seq and isinstance(value, Mapping):
            prepared[name] = _build(dc, value, sub, source)
        elif dc is not None and is_seq:
            prepared[name] = tuple(_build(dc, item, f"{sub}[{i}]", source) for i, item in enumerate(value))
    try:
        return dacite.from_dict(cls, prepared, _DACITE_CONFIG)
    except dacite.UnexpectedDataError as e:
        problems = [f"{where}: unknown key {key!r}.{_suggest(str(key), names)} Allowed keys: {', '.join(names)}."
                    for key in sorted(e.keys, key=str)]
        raise _fail(source, problems) from None
    except dacite.MissingValueError as e:
        name = (e.field_path or "").split(".")[0]
        expected = _type_name(hints[name]) if name in hints else "a value"
        raise _fail(source, [f"{_join(path, e.field_path or '')}: required field is missing "
                             f"(expected {expected})"]) from None
    except dacite.DaciteFieldError as e:
        name = (e.field_path or "").split(".")[0]
        full, tp = _join(path, name), hints.get(name)
        value = data.get(name, getattr(e, "value", None))
        if get_origin(tp) is Literal:
            allowed = [str(a) for a in get_args(tp)]
            msg = (f"{full} = {value!r} is not allowed; allowed values: {', '.join(map(repr, allowed))}."
                   f"{_suggest(str(value), allowed)}")
        elif isinstance(e, dacite.WrongTypeError):
            msg = _wrong_type(full, value, tp)
        else:
            msg = f"{full}: {e}"
        raise _fail(source, [msg]) from None
    except (dacite.DaciteError, TypeError, ValueError) as e:  # pragma: no cover - defensive: one error type out
        raise _fail(source, [f"{where}: {e}"]) from None


# ---------------------------------------------------------------------------------- semantic checks
def _floats(value: Any, path: str) -> Iterator[tuple[str, float]]:
    if isinstance(value, float):
        yield path, value
    elif isinstance(value, Mapping):
        for k, v in value.items():
            yield from _floats(v, _join(path, str(k)))
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            yield from _floats(v, f"{path}[{i}]")


def _semantic_problems(spec: TaskSpec, known_assets: Collection[str] | None) -> list[str]:
    p: list[str] = []

    def need(ok: bool, path: str, value: Any, allowed: str) -> None:
        if not ok:
            p.append(f"{path} = {value!r} is not allowed; {allowed}")

    p += [f"{path} = {v!r} is not allowed; must be a finite number" for path, v in _floats(spec_to_dict(spec), "")
          if not math.isfinite(v)]
    need(bool(TASK_NAME_RE.match(spec.name)), "name", spec.name, "must be CamelCase (^[A-Z][A-Za-z0-9]*$)")
    need(bool(spec.instruction.strip()), "instruction", spec.instruction, "must be a non-empty string")
    need(spec.max_episode_steps >= 1, "max_episode_steps", spec.max_episode_steps, "must be >= 1")
    need(all(s > 0 for s in spec.table.size_m), "table.size_m", list(spec.table.size_m), "both must be > 0")
    need(spec.table.height_m > 0, "table.height_m", spec.table.height_m, "must be > 0")
    need(spec.table.friction > 0, "table.friction", spec.table.friction, "must be > 0")
    if spec.goal is not None:
        need(spec.goal.radius_m > 0, "goal.radius_m", spec.goal.radius_m, "must be > 0")

    need(len(spec.objects) >= 1, "objects", [], "at least one object is required")
    names = [o.name for o in spec.objects]
    seen: set[str] = set()
    lo, hi = SCALE_RANGE
    for i, o in enumerate(spec.objects):
        at = f"objects[{i}]"
        need(bool(SNAKE_NAME_RE.match(o.name)), f"{at}.name", o.name, "must match ^[a-z][a-z0-9_]*$")
        need(o.name != GOAL_TARGET, f"{at}.name", o.name, f"{GOAL_TARGET!r} is reserved for the goal site")
        need(o.name not in seen, f"{at}.name", o.name, "object names must be unique (duplicate name)")
        seen.add(o.name)
        need(bool(o.asset.strip()), f"{at}.asset", o.asset, "must be a non-empty asset id (`gendex assets` lists them)")
        if known_assets is not None and o.asset.strip() and o.asset not in known_assets:
            p.append(f"{at}.asset = {o.asset!r} is not a known asset.{_suggest(o.asset, known_assets)} "
                     f"Run `gendex assets` to list the available asset ids.")
        need(lo <= o.scale <= hi, f"{at}.scale", o.scale, f"allowed range {lo} <= scale <= {hi}")
        need(o.pos_m[2] >= 0, f"{at}.pos_m", list(o.pos_m), "z is the clearance above the table and must be >= 0")
        norm = math.sqrt(sum(q * q for q in o.quat_wxyz))
        need(abs(norm - 1.0) <= QUAT_NORM_TOL, f"{at}.quat_wxyz", list(o.quat_wxyz),
             f"must be a unit quaternion (norm {norm:.4g}, allowed 1 +/- {QUAT_NORM_TOL}); not normalised on load")
        need(all(r >= 0 for r in o.randomize.xy_m), f"{at}.randomize.xy_m", list(o.randomize.xy_m),
             "half-ranges must be >= 0")
        need(o.randomize.yaw_deg >= 0, f"{at}.randomize.yaw_deg", o.randomize.yaw_deg, "half-range must be >= 0")
        if o.color_rgba is not None:
            need(all(0 <= c <= 1 for c in o.color_rgba), f"{at}.color_rgba", list(o.color_rgba),
                 "each channel must be in [0, 1]")

    def ref(value: str | None, path: str, allow_goal: bool = False) -> None:
        if value is None or value in names or (allow_goal and value == GOAL_TARGET and spec.goal is not None):
            return
        options = names + ([GOAL_TARGET] if allow_goal and spec.goal is not None else [])
        extra = (f" ({GOAL_TARGET!r} needs a top-level `goal:`)" if allow_goal and value == GOAL_TARGET else "")
        p.append(f"{path} = {value!r} does not name an object{extra}; allowed: {', '.join(map(repr, options))}."
                 f"{_suggest(value, options)}")

    need(len(spec.stages) >= 1, "stages", [], "at least one stage is required")
    stage_names: set[str] = set()
    for i, s in enumerate(spec.stages):
        at = f"stages[{i}]"
        need(bool(SNAKE_NAME_RE.match(s.name)), f"{at}.name", s.name, "must be snake_case (^[a-z][a-z0-9_]*$)")
        need(s.name not in stage_names, f"{at}.name", s.name, "stage names must be unique (duplicate name)")
        stage_names.add(s.name)
        need(bool(s.instruction.strip()), f"{at}.instruction", s.instruction, "must be a non-empty string")
        need(s.horizon >= 1, f"{at}.horizon", s.horizon, "must be >= 1")
        ref(s.target, f"{at}.target")

    need(bool(spec.success.description.strip()), "success.description", spec.success.description,
         "must be a non-empty string")
    need(spec.success.hold_steps >= 0, "success.hold_steps", spec.success.hold_steps, "must be >= 0")
    need(len(spec.success.conditions) >= 1, "success.conditions", [], "at least one condition is required")
    for i, c in enumerate(spec.success.conditions):
        at = f"success.conditions[{i}]"
        ref(c.object, f"{at}.object")

        def required(fname: str, ok: Any, allowed: str, c: ConditionSpec = c, at: str = at) -> None:
            value = getattr(c, fname)
            if value is None:
                p.append(f"{at}.{fname} is required for type {c.type!r} ({allowed})")
            else:
                need(bool(ok(value)), f"{at}.{fname}", value, f"must be {allowed}")

        if c.type == "lifted":
            required("min_height_m", lambda v: v > 0, "a height in m, > 0")
        elif c.type == "joint_open":
            required("min_fraction", lambda v: 0 < v <= 1, "a fraction in (0, 1]")
        elif c.type in ("inside", "near"):
            required("target", lambda v: v != c.object, "another object's name"
                     + (f" or {GOAL_TARGET!r}" if c.type == "near" else ""))
            if c.target is not None and c.target != c.object:
                ref(c.target, f"{at}.target", allow_goal=c.type == "near")
            if c.type == "near":
                required("max_dist_m", lambda v: v > 0, "a distance in m, > 0")
    return p


# -------------------------------------------------------------------------------------- public API
def parse_task_spec(raw: Mapping, source: str = "<dict>", known_assets: Collection[str] | None = None) -> TaskSpec:
    """Validate an already-parsed task mapping; raise TaskSpecError naming ``source`` on any problem."""
    spec = _build(TaskSpec, raw, "", source)
    problems = _semantic_problems(spec, known_assets)
    if problems:
        raise _fail(source, problems)
    log.debug("parsed task spec %s from %s", spec.name, source)
    return spec


def load_task_spec(path: str | Path, known_assets: Collection[str] | None = None) -> TaskSpec:
    """Read, parse and validate a task YAML file; every problem raises TaskSpecError naming the file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise TaskSpecError(f"cannot read task spec {path}: {e}") from None
    try:
        raw = yaml.load(text, Loader=_UniqueKeyLoader)  # noqa: S506 - SafeLoader subclass
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f", line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        what = " ".join(x for x in (getattr(e, "context", None), getattr(e, "problem", None)) if x) or str(e)
        raise TaskSpecError(f"invalid YAML in {path}{where}: {what}") from None
    if raw is None:
        raise TaskSpecError(f"invalid task spec {path}: the file is empty")
    return parse_task_spec(raw, source=str(path), known_assets=known_assets)


def _plain(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def spec_to_dict(spec: TaskSpec) -> dict:
    """Plain dict of ``spec`` (tuples as lists, every field present, None kept)."""
    return _plain(dataclasses.asdict(spec))


def _drop_none(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _drop_none(v) for k, v in value.items() if v is not None}
    if isinstance(value, list):
        return [_drop_none(v) for v in value]
    return value


class _Dumper(yaml.SafeDumper):
    """SafeDumper writing lists of scalars (vectors) inline and everything else as blocks."""


def _represent_list(dumper: yaml.SafeDumper, data: list) -> yaml.Node:
    flow = all(not isinstance(v, (list, dict)) for v in data)
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)


_Dumper.add_representer(list, _represent_list)


def dump_task_spec(spec: TaskSpec) -> str:
    """YAML text of ``spec``; None-valued (default) fields are omitted. parse(safe_load(dump(s))) == s."""
    return yaml.dump(_drop_none(spec_to_dict(spec)), Dumper=_Dumper, sort_keys=False, allow_unicode=True,
                     default_flow_style=False, width=100)
