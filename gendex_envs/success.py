"""Success: the one authority that decides whether a task, or one of its stages, has succeeded.

Success is declared in the spec (``success.conditions`` for the task, ``stages[k].success`` for a stage) and
evaluated here, batched over ``num_envs``. Reward code cannot grant success: a reward module's ``evaluate`` returns
``fail`` (an episode-ending failure, e.g. the object fell off the table) and diagnostics for its dense reward and
observations, and ``fail`` vetoes success. So for every env and step::

    success = all conditions hold  and  not fail
    fail    = the reward module's fail

The task's ``sequence`` (steps that must happen in order first) and ``hold_steps`` (conditions held that many
consecutive steps) are applied by :class:`SuccessTracker`, which the env owns and resets with each episode. Every
consumer reads success through a :class:`Judge`: the env's ``evaluate`` (and so training, data collection, replay
and evaluation), the stage executor when a stage policy runs, start-state collection, and the generator's critic
(which reads the declared conditions for what the task asks of a scene).

The condition types and their fields are listed in :data:`gendex_envs.conditions.CONDITION_FIELDS`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import torch

from gendex_envs import pouring
from gendex_envs.errors import TaskSpecError
from gendex_envs.geometry import box_rest_point, tilt, xy_distance, z_twist
from gendex_envs.holds import in_holds
from gendex_envs.reward_checks import check_evaluate
from gendex_envs.spec import CONDITION_DEFAULTS, GOAL_TARGET, ConditionSpec, StageSpec, SuccessSpec, TaskSpec

if TYPE_CHECKING:  # pragma: no cover
    from gendex_envs.reward_module import RewardModule
    from gendex_envs.task_env import TaskEnv

INSIDE_FLOOR_TOL_M = 0.01
"""An object counts as inside a container from this far below the container's origin (a seated object may sink
into a thin floor) up to the container's height."""
SET_DOWN_CONDITIONS = ("inside", "over", "near")
"""Conditions that set their object down in, on or by a target: they measure it where it lies (:func:`rest_point`);
the solver sets it down before letting go, and the generator's scene step has it let go and settled."""
THUMB, PALM = 0, 5
"""Rows of the hand's contact-force groups (thumb, index, middle, ring, little, palm)."""
REGION_AHEAD_M = 0.9
"""The table's regions (``placed``, ``in_region``) are measured from the point this far ahead of the robot's base:
x = 0.1 with the base at x = -0.8, the middle of where the library's objects stand (80 % of them at x 0.01-0.58)."""
REGION_MARGIN_M = 0.1
"""An object is in a side region (left, right, near, far) from this far off that point towards it; in the centre
within this of it both ways."""
REGION_DEPTH_M = REGION_MARGIN_M + 0.08
"""Where a solver or a reward aims an object for a side region: this far out from the table's middle point, 8 cm
inside the region (it starts ``REGION_MARGIN_M`` out), so a place a few centimetres off still counts."""
REGION_PARTS = {"left": (1, 1), "right": (1, -1), "near": (0, -1), "far": (0, 1)}
"""Region word -> (axis: 0 forward, 1 left; sign)."""
HUNG_WEIGHT_SHARE = 0.5
"""A ``hung`` object's target bears at least this share of its weight (a mug hung by its handle that leans its body
on the post still hangs; one held up by the hand, its handle just touching the peg, does not)."""
GRAVITY_M_S2 = 9.81


def _param(c: ConditionSpec, name: str):
    value = getattr(c, name)
    return CONDITION_DEFAULTS[name] if value is None else value


def _anchor(env: TaskEnv, c: ConditionSpec) -> torch.Tensor:
    """[N, 3] the point a hand condition refers to: the object's origin, or its handle's grip point."""
    return env.handle_pos(c.object, c.joint) if c.part == "handle" else env.obj_pose(c.object).p


def rest_point(env: TaskEnv, name: str) -> torch.Tensor:
    """[N, 3] where object ``name`` lies, as ``near``, ``over`` and ``inside`` measure it: the centre of its box seen
    from above, at its origin's or its box centre's height, the lower (:func:`~gendex_envs.geometry.box_rest_point`).
    A catalog object's origin is the bottom centre of its box, so an object standing as it was spawned is measured at
    its origin; one that lies on its side at its middle, not at its base; a ball upside down at its centre's height,
    not on its top. An articulated object is measured at its root's origin."""
    pose = env.obj_pose(name)
    if name in env.articulations:
        return pose.p
    record = env.asset_record(name)
    scale = env.task_spec.object(name).scale
    lo, hi = (torch.tensor(b, dtype=pose.p.dtype, device=pose.p.device) * scale
              for b in (record.bbox_min_m, record.bbox_max_m))
    return box_rest_point(pose.p, pose.q, lo, hi)


def robot_axes(env: TaskEnv, like: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """The robot's view of the table as [2] tensors (dtype and device of ``like``): its base's xy, the direction it
    faces (forward: away from it) and its left."""
    robot = env.task_spec.robot
    yaw = math.radians(robot.base_yaw_deg)
    as_t = lambda v: torch.tensor(v, dtype=like.dtype, device=like.device)  # noqa: E731
    return (as_t(robot.base_pos_m[:2]), as_t([math.cos(yaw), math.sin(yaw)]),
            as_t([-math.sin(yaw), math.cos(yaw)]))


def _placed(env: TaskEnv, c: ConditionSpec) -> torch.Tensor:
    """[N] where the object lies (:func:`rest_point`) against the relation, seen from the robot."""
    p = rest_point(env, c.object)[:, :2]
    base, fwd, left = robot_axes(env, p)
    if c.relation == "in_region":
        d = p - (base + REGION_AHEAD_M * fwd)
        along = (d @ fwd, d @ left)
        if c.region == "centre":
            return (along[0].abs() <= REGION_MARGIN_M) & (along[1].abs() <= REGION_MARGIN_M)
        ok = torch.ones(p.shape[0], dtype=torch.bool, device=p.device)
        for part in c.region.split("_"):
            axis, sign = REGION_PARTS[part]
            ok = ok & (sign * along[axis] >= REGION_MARGIN_M)
        return ok
    lo, offset = _param(c, "min_gap_m"), _param(c, "max_offset_m")
    a = rest_point(env, c.target)[:, :2]
    d = p - a
    if c.relation == "between":
        u = rest_point(env, c.other)[:, :2] - a
        length = torch.linalg.norm(u, dim=-1).clamp_min(1e-9)
        u = u / length[:, None]
        t = (d * u).sum(-1)
        across = (d[:, 0] * u[:, 1] - d[:, 1] * u[:, 0]).abs()
        return (t >= lo) & (length - t >= lo) & (across <= offset)
    hi = _param(c, "max_gap_m")
    if c.relation == "next_to":
        r = torch.linalg.norm(d, dim=-1)
        return (r >= lo) & (r <= hi)
    axis = {"left_of": left, "right_of": -left, "behind": fwd, "in_front_of": -fwd}[c.relation]
    side = fwd if c.relation in ("left_of", "right_of") else left
    along = d @ axis
    return (along >= lo) & (along <= hi) & ((d @ side).abs() <= offset)


def _weight_n(env: TaskEnv, name: str) -> float:
    """Object ``name``'s weight (N): its catalog mass at its scale (uniform scaling keeps the density)."""
    scale = env.task_spec.object(name).scale
    return env.asset_record(name).entry.mass_kg * scale**3 * GRAVITY_M_S2


def in_container(env: TaskEnv, name: str, target: str) -> torch.Tensor:
    """[N] object ``name`` lies in rigid container ``target`` (the ``inside`` condition without a joint)."""
    inner_r, top = env.container_extent(target)
    box, p = env.obj_pose(target).p, rest_point(env, name)
    dz = p[:, 2] - box[:, 2]
    return (xy_distance(p, box) <= inner_r) & (dz >= -INSIDE_FLOOR_TOL_M) & (dz <= top)


def _holds(env: TaskEnv, c: ConditionSpec) -> torch.Tensor:
    t = c.type
    if t == "placed":
        return _placed(env, c)
    if t == "joint_at":
        return (env.joint_open_fraction(c.object, c.joint) - c.fraction).abs() <= _param(c, "max_error")
    if t == "lifted":
        return env.obj_height(c.object) >= c.min_height_m
    if t == "joint_open":
        return env.joint_open_fraction(c.object, c.joint) >= c.min_fraction
    if t == "near":
        target = env.goal_pos if c.target == GOAL_TARGET else env.obj_pose(c.target).p
        return torch.linalg.norm(rest_point(env, c.object) - target, dim=-1) <= c.max_dist_m
    if t == "inside":
        if c.joint is not None:
            return in_holds(env, c.target, c.joint, rest_point(env, c.object))
        return in_container(env, c.object, c.target)
    if t == "poured":
        return pouring.share(env, c.object, c.target) >= c.min_fraction - 1e-6
    if t == "rotated":
        twist = z_twist(env.obj_pose(c.object).q, env.init_obj_quat(c.object))
        goal = math.radians(c.min_deg)
        return twist >= goal if goal > 0 else twist <= goal
    if t in ("upright", "flipped"):
        angle = tilt(env.obj_pose(c.object).q, env.init_obj_quat(c.object))
        if t == "upright":
            return angle <= math.radians(_param(c, "max_tilt_deg"))
        return angle >= math.radians(_param(c, "min_tilt_deg"))
    if t == "at_rest":
        obj = env.obj(c.object)
        lin, ang = ((obj.root_linear_velocity, obj.root_angular_velocity) if c.object in env.articulations
                    else (obj.linear_velocity, obj.angular_velocity))
        return ((torch.linalg.norm(lin, dim=-1) <= _param(c, "max_speed_m_s"))
                & (torch.linalg.norm(ang, dim=-1) <= _param(c, "max_spin_rad_s")))
    if t == "wiped":
        return env.wipes.share(c) >= c.min_fraction - 1e-6
    if t == "hung":
        force = env.scene.get_pairwise_contact_forces(env.obj(c.object), env.obj(c.target))  # [N, 3]
        return ((torch.linalg.norm(force, dim=-1) >= HUNG_WEIGHT_SHARE * _weight_n(env, c.object))
                & (env.obj_height(c.object) >= _param(c, "min_height_m")))
    if t == "over":
        p, q = rest_point(env, c.object), env.obj_pose(c.target).p
        dz = p[:, 2] - q[:, 2]
        return (xy_distance(p, q) <= c.max_xy_m) & (dz >= c.min_dz_m) & (dz <= c.max_dz_m)
    if t in ("grasped", "released"):
        force = env.hand_forces(c.object, part=c.part, joint=c.joint)  # [N, 6]
        if t == "released":
            return (force <= _param(c, "max_force_n")).all(dim=1)
        touching = force > _param(c, "min_force_n")
        ok = touching[:, THUMB + 1:PALM].sum(dim=1) >= _param(c, "min_fingers")
        if _param(c, "thumb"):
            ok = ok & touching[:, THUMB]
        if c.max_palm_force_n is not None:
            ok = ok & (force[:, PALM] <= c.max_palm_force_n)
        return ok
    if t == "hand_at":
        point, palm = _anchor(env, c), env.palm_pose.p
        ring = _param(c, "ring_radius_m")
        if ring > 0:  # the nearest point of the ring about the vertical axis: any side will do
            d = palm[:, :2] - point[:, :2]
            side = d / torch.linalg.norm(d, dim=-1, keepdim=True).clamp_min(1e-6)
            goal = torch.cat([point[:, :2] + ring * side, point[:, 2:] + _param(c, "above_m")], dim=-1)
        else:
            goal = point.clone()
            goal[:, 2] += _param(c, "above_m")
        return torch.linalg.norm(palm - goal, dim=-1) <= c.max_dist_m
    if t == "fingertips_near":
        point = _anchor(env, c)
        return torch.linalg.norm(env.tip_positions - point[:, None, :], dim=-1).mean(dim=1) <= c.max_dist_m
    if t == "hand_open":
        spread = torch.linalg.norm(env.tip_positions - env.palm_pose.p[:, None, :], dim=-1).mean(dim=1)
        return spread >= c.min_spread_m
    raise TaskSpecError(f"unknown condition type {t!r}")


def condition_holds(env: TaskEnv, c: ConditionSpec) -> torch.Tensor:
    """[N] bool: condition ``c`` holds now in each env."""
    ok = _holds(env, c)
    return ~ok if c.negate else ok


def conditions_hold(env: TaskEnv, conditions: tuple[ConditionSpec, ...]) -> torch.Tensor:
    """[N] bool: every condition holds now."""
    ok = torch.ones(env.num_envs, dtype=torch.bool, device=env.device)
    for c in conditions:
        ok = ok & condition_holds(env, c)
    return ok


@dataclass(frozen=True)
class Judge:
    """Decides success of the task or of one stage: the declared conditions, vetoed by the reward module's fail."""

    label: str
    """What is judged, for messages ("task PutAppleBowl", "stage grasp_apple of PutAppleBowl")."""
    conditions: tuple[ConditionSpec, ...]
    module: RewardModule
    """The reward module whose ``evaluate`` gives ``fail`` and the diagnostics its reward and observations use."""
    stage: str | None = None
    """The stage judged (None: the whole task)."""

    @classmethod
    def of_task(cls, spec: TaskSpec, module: RewardModule) -> Judge:
        return cls(f"task {spec.name}", spec.success.conditions, module)

    @classmethod
    def of_stage(cls, spec: TaskSpec, stage: StageSpec, module: RewardModule) -> Judge:
        return cls(f"stage {stage.name} of {spec.name}", spec.stage_conditions(stage), module, stage.name)

    def evaluate(self, env: TaskEnv) -> dict[str, torch.Tensor]:
        """The module's diagnostics with ``success`` and ``fail`` ([N] bool) decided as the module doc says. What
        the module returns is checked on every call (:func:`gendex_envs.reward_checks.check_evaluate`: no
        ``success`` or other reserved key, [N] tensors, finite values); a broken rule raises
        :class:`~gendex_envs.reward_checks.RewardOutputError`."""
        n = env.num_envs
        info = check_evaluate(self.module.evaluate(env), n, env.device, path=self.module.path,
                              step=getattr(env, "elapsed_steps", None))
        fail = info.get("fail")
        if fail is None:
            fail = torch.zeros(n, dtype=torch.bool, device=env.device)
        info["success"] = conditions_hold(env, self.conditions) & ~fail
        info["fail"] = fail
        return info


class SuccessTracker:
    """The task's success across the steps of an episode, per env: how far the ordered ``success.sequence`` has come
    (a step, once done, stays done) and the streaks ``hold_steps`` count. The env owns one, resets it with each
    episode and feeds it the judge's verdict on the final conditions; each control step is counted once, however
    often ``evaluate`` is called within it.

    A sequence step is done at the first control step at which its conditions have held for its ``hold_steps``
    (at least that step) while it was the current one; the next step becomes current at the next control step, and
    after the last one the task's ``conditions`` (with ``hold_steps`` and ``fail``) decide success."""

    def __init__(self, success: SuccessSpec, num_envs: int, device: torch.device | str):
        self.steps = success.sequence or ()
        self.hold = success.hold_steps
        with torch.device(device):
            self.progress = torch.zeros(num_envs, dtype=torch.long)
            """[N] sequence steps done."""
            self.streak = torch.zeros(num_envs, dtype=torch.long)
            """[N] consecutive control steps the current step's (or, after the sequence, the task's) conditions held."""
            self.counted_at = torch.full((num_envs,), -1, dtype=torch.long)

    def reset(self, env_idx: torch.Tensor) -> None:
        self.progress[env_idx] = 0
        self.streak[env_idx] = 0
        self.counted_at[env_idx] = -1

    def update(self, env: TaskEnv, holds: torch.Tensor, step: torch.Tensor) -> torch.Tensor:
        """[N] bool success, given ``holds`` (the task's conditions hold now and no fail) at control step ``step``."""
        if not self.steps and self.hold == 0:
            return holds
        fresh = self.counted_at != step
        self.counted_at = torch.where(fresh, step, self.counted_at)
        final = self.progress >= len(self.steps)  # the sequence was done before this call
        if self.steps:
            now = torch.zeros_like(holds)
            need = torch.ones_like(self.progress)
            for k, s in enumerate(self.steps):  # every step for every env: no host sync on the GPU backend
                at = self.progress == k
                now = torch.where(at, conditions_hold(env, s.conditions), now)
                need = torch.where(at, max(s.hold_steps, 1), need)
            counting = fresh & ~final
            self.streak = torch.where(counting, (self.streak + 1) * now, self.streak)
            advance = counting & (self.streak >= need)
            self.progress = self.progress + advance.long()
            self.streak = torch.where(advance, 0, self.streak)
        if self.hold == 0:
            return final & holds
        self.streak = torch.where(final & fresh, (self.streak + 1) * holds, self.streak)
        return final & (self.streak >= self.hold)

