"""Typed schema of a task YAML file (the spec of a task version, see :mod:`gendex_envs.task_version`).

A task file is loaded with dacite in strict mode into the frozen dataclasses below (:mod:`gendex_envs.typed_yaml`),
then checked semantically (ranges, name patterns, cross references, which fields each condition type takes). Every
problem is reported as one :class:`~gendex_envs.errors.TaskSpecError` naming the file, the field path
(``objects[1].scale``), the bad value and what is allowed. Lengths are in metres, angles in degrees. The table top is
the world plane z = 0. See ``docs/task_spec.md`` for the field reference and a full example.

Success is declared here and nowhere else: ``success.conditions`` (after the steps of ``success.sequence``, in
order) for the whole task and ``stages[k].success`` for a stage (a stage that declares none succeeds when the task
does). :mod:`gendex_envs.success` evaluates them; :mod:`gendex_envs.conditions` defines the condition types.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import re
from collections.abc import Collection, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, get_args

import numpy as np
import yaml

from gendex_envs.attributes import COLORS, ColorName
from gendex_envs.conditions import (  # noqa: F401 - the spec's names for them
    CONDITION_DEFAULTS,
    CONDITION_FIELDS,
    CONDITION_TYPES,
    REGIONS,
    RELATIONS,
    ConditionSpec,
    ConditionType,
    Part,
    condition_problems,
)
from gendex_envs.errors import StageError, TaskSpecError, suggest
from gendex_envs.scene_spec import SceneSpec, scene_problems
from gendex_envs.typed_yaml import (
    MAX_CONDITIONS,
    MAX_INPUT_BYTES,
    MAX_JOINT_STATES,
    MAX_OBJECTS,
    MAX_POSITION_M,
    MAX_STAGES,
    MAX_STEPS,
    MAX_STRING_CHARS,
    bounded_field,
    build,
    join_path,
    load_yaml_bounded,
    quote,
    spec_error,
    suggest_value,
)

log = logging.getLogger(__name__)

RobotUid = Literal["ur10e_shadow"]
Keyframe = Literal["rest", "pregrasp_open", "palm_up"]
StageMethod = Literal["motion_planning", "RL"]
ControlJoint = Literal["arm", "hand", "both", "three_finger", "arm_two_finger", "lift_inspire"]
Skill = Literal["reach", "grasp", "lift", "carry", "place", "release", "open", "close", "push", "turn", "reorient",
                "press", "twist", "wipe", "hang", "pour", "flip"]

ROBOT_UIDS: tuple[str, ...] = get_args(RobotUid)
KEYFRAMES: tuple[str, ...] = get_args(Keyframe)
STAGE_METHODS: tuple[str, ...] = get_args(StageMethod)
CONTROL_JOINT_MODES: tuple[str, ...] = get_args(ControlJoint)
SKILLS: tuple[str, ...] = get_args(Skill)

SKILL_MEANINGS: dict[str, str] = {
    "reach": "bring the open hand to where the next skill starts (a pre-grasp pose, a handle)",
    "grasp": "close the fingers on the target (a rigid object: hold it; an articulated one: hook its handle)",
    "lift": "raise the held target off its support",
    "carry": "move the held object to above another object or place",
    "place": "set the held object down on or into its destination",
    "release": "open the hand and let go of the held target",
    "open": "open the target's joint (a door, a lid, a drawer) by its handle",
    "close": "close the target's joint by its handle",
    "push": "push or slide the target across its support without grasping it",
    "turn": "turn the target about its own axis (a knob, a valve, a lid)",
    "reorient": "rotate the target inside the hand (in-hand manipulation)",
    "press": "press a button or switch past its detent to its other rest position, without grasping it",
    "twist": "unscrew (or screw on) the target's cap about its own axis, regrasping it between turns of the hand",
    "wipe": "slide the held object (a sponge) over the target's marks (a spill), pressed down on it",
    "hang": "thread the held object's handle (a mug's) onto a peg of the target (a hook or mug tree) and lower it "
            "onto the peg",
    "pour": "tip the held vessel over the target (a bowl) until the loose pieces in it (beads) fall in, then stand it "
            "up again",
    "flip": "turn the held object upside down (about the fingers' line) and set it down on the table on its top",
}
"""What each skill of :data:`SKILLS` does; the stage's ``target`` is the object it acts on."""
assert set(SKILL_MEANINGS) == set(SKILLS)
JOINT_SKILLS: tuple[str, ...] = ("open", "close", "turn", "press", "twist")
"""Stage skills that move an articulated target's joint (its success: the joint's fraction)."""

SCALE_RANGE: tuple[float, float] = (0.3, 2.0)
QUAT_NORM_TOL = 1e-3
GOAL_TARGET = "goal"
"""Reserved name: a ``near`` condition with ``target: goal`` refers to the task's goal site."""
TASK_NAME_RE = re.compile(r"\A[A-Z][A-Za-z0-9]*\Z")
"""A task name: ASCII CamelCase, the whole string (``\\Z``: a ``$`` would also match before a final newline)."""
SNAKE_NAME_RE = re.compile(r"\A[a-z][a-z0-9_]*\Z")
"""An object or stage name: ASCII snake_case, the whole string."""

MAX_RANDOMIZE_M = 1.0
"""Bound (m) on a randomization half-range (``randomize.xy_m``); the committed library's largest is 0.13 m."""
MAX_ANGLE_DEG = 360.0
"""Bound (degrees) on ``randomize.yaw_deg`` (a half-range; the committed library's largest is 180) and on
``robot.base_yaw_deg``."""
MAX_JOINT_POSITION = 40.0
"""Bound on an initial joint position (``joint_state``, rad or m): about six turns of a screw cap; the committed
library's largest is 6.28 (a cap a full turn off its thread). The env also checks each one against its joint's
limits when it builds the scene (the asset is known only there)."""
MAX_TABLE_M = 50.0
"""Bound (m) on the table's size and height; the committed tables are 1.6 m x 1.2 m, 0.76 m high."""


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
    joint_state: dict[str, float] = bounded_field(MAX_JOINT_STATES, "joint states", "MAX_JOINT_STATES",
                                             default_factory=dict)
    """Initial joint positions by joint name, for articulated assets only."""
    randomize: RandomizeSpec = field(default_factory=RandomizeSpec)
    """Pose noise applied at reset (layouts are drawn free of overlaps between objects)."""
    color_rgba: tuple[float, float, float, float] | None = None
    """Optional colour override, each channel in [0, 1]."""
    color: ColorName | None = None
    """Optional named colour (``gendex_envs.attributes.COLORS``) the object is painted in, instead of color_rgba."""
    distractor: bool = False
    """True for clutter the task is not about: no stage acts on it and no condition names it; solvers avoid it."""

    @property
    def rgba(self) -> tuple[float, float, float, float] | None:
        """The colour the object is painted in (its named colour's or color_rgba), None: the asset's own."""
        return COLORS[self.color] if self.color is not None else self.color_rgba


@dataclass(frozen=True, kw_only=True)
class GoalSpec:
    """An optional goal site shown in the scene."""

    pos_m: tuple[float, float, float]
    """World position of the goal (m); z measured from the table top."""
    radius_m: float = 0.05
    """Radius of the goal sphere (m), > 0."""


@dataclass(frozen=True, kw_only=True)
class StageSpec:
    """One stage of the task: a skill applied to a target, solved by motion planning or RL."""

    name: str
    """Stage identifier, snake_case (^[a-z][a-z0-9_]*$); unique within the task."""
    instruction: str
    """Non-empty natural-language description of the stage."""
    skill: Skill
    """What the stage does; one of SKILLS (see SKILL_MEANINGS). The solver, stage rewards and critic read it."""
    method: StageMethod
    """Solver; one of STAGE_METHODS."""
    control_joint: ControlJoint
    """Which joints the stage controls; one of CONTROL_JOINT_MODES."""
    horizon: int = 100
    """Number of control steps of the stage, >= 1."""
    target: str | None = None
    """Optional name of the object the stage acts on."""
    success: tuple[ConditionSpec, ...] | None = bounded_field(MAX_CONDITIONS, "conditions", "MAX_CONDITIONS",
                                                         default=None)
    """When the stage has done its job (all must hold); None: when the task's success holds."""


@dataclass(frozen=True, kw_only=True)
class SequenceStepSpec:
    """One step of a task's ordered sequence: something that must have happened, after the steps before it."""

    description: str
    """Non-empty natural-language description of the step ("the apple has been lifted")."""
    conditions: tuple[ConditionSpec, ...] = bounded_field(MAX_CONDITIONS, "conditions", "MAX_CONDITIONS")
    """At least one condition; the step is done once all hold (for ``hold_steps``) after the previous step was done."""
    hold_steps: int = 0
    """Number of consecutive steps the conditions must hold, >= 0."""


@dataclass(frozen=True, kw_only=True)
class SuccessSpec:
    """When the task counts as solved."""

    description: str
    """Non-empty natural-language description of success."""
    conditions: tuple[ConditionSpec, ...] = bounded_field(MAX_CONDITIONS, "conditions", "MAX_CONDITIONS")
    """At least one condition; all must hold."""
    hold_steps: int = 0
    """Number of consecutive steps the conditions must hold, >= 0."""
    sequence: tuple[SequenceStepSpec, ...] | None = bounded_field(MAX_STAGES, "sequence steps", "MAX_STAGES",
                                                             default=None)
    """Steps that must happen in this order before ``conditions`` count ("A, then B, then C": A and B here, C in
    ``conditions``); a step, once done, stays done. None: no order, only ``conditions``."""


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
    objects: tuple[ObjectSpec, ...] = bounded_field(MAX_OBJECTS, "objects",
                                               "MAX_OBJECTS: SAPIEN crashes past its material limit")
    """Objects in the scene, at least one and at most MAX_OBJECTS; names unique."""
    goal: GoalSpec | None = None
    """Optional goal site."""
    stages: tuple[StageSpec, ...] = bounded_field(MAX_STAGES, "stages", "MAX_STAGES")
    """Stages in execution order, at least one and at most MAX_STAGES."""
    success: SuccessSpec
    """Success criterion."""
    max_episode_steps: int = 200
    """Episode length limit in control steps, >= 1."""
    scene: SceneSpec | None = None
    """What the place looks like (:mod:`gendex_envs.scene_spec`); None: the plain table, floor and lights."""

    def object(self, name: str) -> ObjectSpec:
        """Return the object called ``name``; TaskSpecError (with suggestions) if there is none."""
        for obj in self.objects:
            if obj.name == name:
                return obj
        names = [o.name for o in self.objects]
        raise TaskSpecError(f"task {self.name!r} has no object {quote(name)}; objects: {', '.join(names)}."
                            f"{suggest_value(name, names)}")

    def stage_conditions(self, stage: StageSpec) -> tuple[ConditionSpec, ...]:
        """What decides ``stage``'s success: its own conditions, else the task's."""
        return stage.success if stage.success is not None else self.success.conditions


def resolve_stage(spec: TaskSpec, stage: str | int) -> tuple[int, StageSpec]:
    """(index, spec) of ``stage`` given by name or index; :class:`StageError` naming the stages otherwise."""
    names = [s.name for s in spec.stages]
    if isinstance(stage, (int, np.integer)) and not isinstance(stage, bool):
        if not 0 <= int(stage) < len(names):
            raise StageError(f"task {spec.name!r} has no stage {int(stage)}; stages 0..{len(names) - 1}: {names}")
        return int(stage), spec.stages[int(stage)]
    if isinstance(stage, str) and stage.isdigit():
        return resolve_stage(spec, int(stage))
    if stage not in names:
        raise StageError(f"task {spec.name!r} has no stage {stage!r}; stages: {names}.{suggest(str(stage), names)}")
    return names.index(stage), spec.stages[names.index(stage)]


# ---------------------------------------------------------------------------------- semantic checks
def _leaves(value: Any, path: str) -> Iterator[tuple[str, Any]]:
    if isinstance(value, Mapping):
        for k, v in value.items():
            yield from _leaves(v, join_path(path, str(k)))
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            yield from _leaves(v, f"{path}[{i}]")
    else:
        yield path, value


def _leaf_problems(spec: TaskSpec) -> list[str]:
    """Non-finite numbers and over-long strings anywhere in ``spec`` (a parsed mapping may not come from YAML)."""
    p: list[str] = []
    for path, v in _leaves(spec_to_dict(spec), ""):
        if isinstance(v, float) and not math.isfinite(v):
            p.append(f"{path} = {v!r} is not allowed; must be a finite number")
        elif isinstance(v, str) and len(v) > MAX_STRING_CHARS:
            p.append(f"{path} = {quote(v)} is not allowed; at most {MAX_STRING_CHARS} characters (MAX_STRING_CHARS)")
    return p


def _semantic_problems(spec: TaskSpec, known_assets: Collection[str] | None) -> list[str]:
    p: list[str] = []

    def need(ok: bool, path: str, value: Any, allowed: str) -> None:
        if not ok:
            p.append(f"{path} = {quote(value)} is not allowed; {allowed}")

    def within(position: tuple[float, ...], path: str) -> None:
        need(all(abs(x) <= MAX_POSITION_M for x in position), path, list(position),
             f"each coordinate must be within +/-{MAX_POSITION_M} m (MAX_POSITION_M)")

    p += _leaf_problems(spec)
    need(bool(TASK_NAME_RE.fullmatch(spec.name)), "name", spec.name,
         "must be ASCII CamelCase, the whole name ([A-Z][A-Za-z0-9]*)")
    need(bool(spec.instruction.strip()), "instruction", spec.instruction, "must be a non-empty string")
    need(1 <= spec.max_episode_steps <= MAX_STEPS, "max_episode_steps", spec.max_episode_steps,
         f"must be >= 1 and <= {MAX_STEPS} (MAX_STEPS)")
    need(all(s > 0 for s in spec.table.size_m), "table.size_m", list(spec.table.size_m), "both must be > 0")
    need(spec.table.height_m > 0, "table.height_m", spec.table.height_m, "must be > 0")
    need(all(s <= MAX_TABLE_M for s in spec.table.size_m), "table.size_m", list(spec.table.size_m),
         f"each must be <= {MAX_TABLE_M} m (MAX_TABLE_M)")
    need(spec.table.height_m <= MAX_TABLE_M, "table.height_m", spec.table.height_m,
         f"must be <= {MAX_TABLE_M} m (MAX_TABLE_M)")
    within(spec.robot.base_pos_m, "robot.base_pos_m")
    need(abs(spec.robot.base_yaw_deg) <= MAX_ANGLE_DEG, "robot.base_yaw_deg", spec.robot.base_yaw_deg,
         f"must be within +/-{MAX_ANGLE_DEG} degrees (MAX_ANGLE_DEG)")
    need(spec.table.friction > 0, "table.friction", spec.table.friction, "must be > 0")
    if spec.goal is not None:
        need(0 < spec.goal.radius_m <= MAX_POSITION_M, "goal.radius_m", spec.goal.radius_m,
             f"must be > 0 and <= {MAX_POSITION_M} m (MAX_POSITION_M)")
        within(spec.goal.pos_m, "goal.pos_m")

    need(len(spec.objects) >= 1, "objects", [], "at least one object is required")
    names = [o.name for o in spec.objects]
    seen: set[str] = set()
    lo, hi = SCALE_RANGE
    for i, o in enumerate(spec.objects):
        at = f"objects[{i}]"
        need(bool(SNAKE_NAME_RE.fullmatch(o.name)), f"{at}.name", o.name,
             "must be ASCII snake_case, the whole name ([a-z][a-z0-9_]*)")
        need(o.name != GOAL_TARGET, f"{at}.name", o.name, f"{GOAL_TARGET!r} is reserved for the goal site")
        need(o.name != "palm", f"{at}.name", o.name, "'palm' is reserved: the env's own observation palm_pose is the "
             "hand's, and an object's pose is observed as <name>_pose")
        need(o.name not in seen, f"{at}.name", o.name, "object names must be unique (duplicate name)")
        seen.add(o.name)
        need(bool(o.asset.strip()), f"{at}.asset", o.asset, "must be a non-empty asset id (`gendex assets` lists them)")
        if known_assets is not None and o.asset.strip() and o.asset not in known_assets:
            p.append(f"{at}.asset = {quote(o.asset)} is not a known asset.{suggest_value(o.asset, known_assets)} "
                     f"Run `gendex assets` to list the available asset ids.")
        need(lo <= o.scale <= hi, f"{at}.scale", o.scale, f"allowed range {lo} <= scale <= {hi}")
        need(o.pos_m[2] >= 0, f"{at}.pos_m", list(o.pos_m), "z is the clearance above the table and must be >= 0")
        within(o.pos_m, f"{at}.pos_m")
        for joint, value in o.joint_state.items():
            need(abs(value) <= MAX_JOINT_POSITION, join_path(f"{at}.joint_state", str(joint)), value,
                 f"must be within +/-{MAX_JOINT_POSITION} (MAX_JOINT_POSITION, rad or m)")
        norm = math.sqrt(sum(q * q for q in o.quat_wxyz))
        need(abs(norm - 1.0) <= QUAT_NORM_TOL, f"{at}.quat_wxyz", list(o.quat_wxyz),
             f"must be a unit quaternion (norm {norm:.4g}, allowed 1 +/- {QUAT_NORM_TOL}); not normalised on load")
        need(all(r >= 0 for r in o.randomize.xy_m), f"{at}.randomize.xy_m", list(o.randomize.xy_m),
             "half-ranges must be >= 0")
        need(all(r <= MAX_RANDOMIZE_M for r in o.randomize.xy_m), f"{at}.randomize.xy_m", list(o.randomize.xy_m),
             f"half-ranges must be <= {MAX_RANDOMIZE_M} m (MAX_RANDOMIZE_M)")
        need(0 <= o.randomize.yaw_deg <= MAX_ANGLE_DEG, f"{at}.randomize.yaw_deg", o.randomize.yaw_deg,
             f"half-range must be >= 0 and <= {MAX_ANGLE_DEG} degrees (MAX_ANGLE_DEG)")
        if o.color_rgba is not None:
            need(all(0 <= c <= 1 for c in o.color_rgba), f"{at}.color_rgba", list(o.color_rgba),
                 "each channel must be in [0, 1]")
            need(o.color is None, f"{at}.color_rgba", list(o.color_rgba),
                 f"give color ({o.color!r}) or color_rgba, not both")

    def ref(value: str | None, path: str, allow_goal: bool = False) -> None:
        if value is None or value in names or (allow_goal and value == GOAL_TARGET and spec.goal is not None):
            return
        options = names + ([GOAL_TARGET] if allow_goal and spec.goal is not None else [])
        extra = (f" ({GOAL_TARGET!r} needs a top-level `goal:`)" if allow_goal and value == GOAL_TARGET else "")
        p.append(f"{path} = {quote(value)} does not name an object{extra}; allowed: {', '.join(map(repr, options))}."
                 f"{suggest_value(value, options)}")

    distractors = {o.name for o in spec.objects if o.distractor}

    def not_distractor(value: str | None, path: str) -> None:
        if value in distractors:
            p.append(f"{path} = {quote(value)} names a distractor (objects with distractor: true take part in no stage "
                     "or condition); name a task object or drop the distractor flag")

    if spec.scene is not None:
        p += scene_problems(spec.scene, "scene", tuple(names))
    need(len(spec.stages) >= 1, "stages", [], "at least one stage is required")
    stage_names: set[str] = set()
    for i, s in enumerate(spec.stages):
        at = f"stages[{i}]"
        need(bool(SNAKE_NAME_RE.fullmatch(s.name)), f"{at}.name", s.name,
             "must be ASCII snake_case, the whole name ([a-z][a-z0-9_]*)")
        need(s.name not in stage_names, f"{at}.name", s.name, "stage names must be unique (duplicate name)")
        stage_names.add(s.name)
        need(bool(s.instruction.strip()), f"{at}.instruction", s.instruction, "must be a non-empty string")
        need(1 <= s.horizon <= MAX_STEPS, f"{at}.horizon", s.horizon, f"must be >= 1 and <= {MAX_STEPS} (MAX_STEPS)")
        ref(s.target, f"{at}.target")
        not_distractor(s.target, f"{at}.target")
        if s.success is not None:
            need(len(s.success) >= 1, f"{at}.success", [], "leave it out (the stage then succeeds with the task) "
                 "or give at least one condition")
            for j, c in enumerate(s.success):
                p += condition_problems(c, f"{at}.success[{j}]", ref)
                not_distractor(c.object, f"{at}.success[{j}].object")
                not_distractor(c.target, f"{at}.success[{j}].target")

    need(bool(spec.success.description.strip()), "success.description", spec.success.description,
         "must be a non-empty string")
    need(0 <= spec.success.hold_steps <= MAX_STEPS, "success.hold_steps", spec.success.hold_steps,
         f"must be >= 0 and <= {MAX_STEPS} (MAX_STEPS)")
    need(len(spec.success.conditions) >= 1, "success.conditions", [], "at least one condition is required")
    groups = [("success", spec.success.conditions)]
    if spec.success.sequence is not None:
        need(len(spec.success.sequence) >= 1, "success.sequence", [], "leave it out (no order) or give at least one "
             "step")
        for k, step in enumerate(spec.success.sequence):
            at = f"success.sequence[{k}]"
            need(bool(step.description.strip()), f"{at}.description", step.description, "must be a non-empty string")
            need(0 <= step.hold_steps <= MAX_STEPS, f"{at}.hold_steps", step.hold_steps,
                 f"must be >= 0 and <= {MAX_STEPS} (MAX_STEPS)")
            need(len(step.conditions) >= 1, f"{at}.conditions", [], "at least one condition is required")
            groups.append((at, step.conditions))
    for at, conditions in groups:
        for i, c in enumerate(conditions):
            p += condition_problems(c, f"{at}.conditions[{i}]", ref)
            not_distractor(c.object, f"{at}.conditions[{i}].object")
            not_distractor(c.target, f"{at}.conditions[{i}].target")
    return p


# -------------------------------------------------------------------------------------- public API
def parse_task_spec(raw: Mapping, source: str = "<dict>", known_assets: Collection[str] | None = None) -> TaskSpec:
    """Validate an already-parsed task mapping; raise TaskSpecError naming ``source`` on any problem."""
    spec = build(TaskSpec, raw, "", source)
    problems = _semantic_problems(spec, known_assets)
    if problems:
        raise spec_error(source, problems)
    log.debug("parsed task spec %s from %s", spec.name, source)
    return spec


def load_task_spec(path: str | Path, known_assets: Collection[str] | None = None) -> TaskSpec:
    """Read, parse and validate a task YAML file; every problem raises TaskSpecError naming the file.

    The file is untrusted: one larger than MAX_INPUT_BYTES is refused before it is read whole, and the YAML is
    parsed with the bounds of :func:`~gendex_envs.typed_yaml.load_yaml_bounded` (no anchors or aliases, capped
    depth, node count, string length)."""
    path = Path(path)
    try:
        with path.open("rb") as fh:
            data = fh.read(MAX_INPUT_BYTES + 1)  # never read more than the bound (a file may be huge or endless)
    except OSError as e:
        raise TaskSpecError(f"cannot read task spec {path}: {e}") from None
    if len(data) > MAX_INPUT_BYTES:
        raise TaskSpecError(f"task spec {path} is larger than {MAX_INPUT_BYTES} bytes; at most {MAX_INPUT_BYTES} "
                            "bytes are allowed (MAX_INPUT_BYTES; refused before parsing)")
    raw = load_yaml_bounded(data, str(path), TaskSpecError)
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


def omit_unset(value: Any) -> Any:
    """A plain spec mapping (or list) without what a reader need not see: None-valued fields, the conditions'
    default ``negate: false`` and the objects' default ``distractor: false``."""
    if isinstance(value, dict):
        return {k: omit_unset(v) for k, v in value.items()
                if v is not None and not (k == "negate" and v is False and "type" in value)
                and not (k == "distractor" and v is False and "asset" in value)}
    if isinstance(value, list):
        return [omit_unset(v) for v in value]
    return value


class _Dumper(yaml.SafeDumper):
    """SafeDumper writing lists of scalars (vectors) inline and everything else as blocks; never anchors or aliases
    (the loader refuses them)."""

    def ignore_aliases(self, data: Any) -> bool:
        return True


def _represent_list(dumper: yaml.SafeDumper, data: list) -> yaml.Node:
    flow = all(not isinstance(v, (list, dict)) for v in data)
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)


_Dumper.add_representer(list, _represent_list)


def dump_task_spec(spec: TaskSpec) -> str:
    """YAML text of ``spec``; None-valued (default) fields are omitted. parse(safe_load(dump(s))) == s."""
    return yaml.dump(omit_unset(spec_to_dict(spec)), Dumper=_Dumper, sort_keys=False, allow_unicode=True,
                     default_flow_style=False, width=100)
