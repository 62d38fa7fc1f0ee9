"""Where the solver sets a held object down for a ``placed`` condition (*put the apple to the left of the bowl*, *move
the block to the far left of the table*): a point on the table top, from the condition and where things are now.

The point is in the middle of what the condition accepts (:func:`gendex_envs.success._placed` measures it): for a
side relation, the middle of the ``min_gap_m``..``max_gap_m`` band straight out from the target on that side, as the
robot sees it; ``between``, the midpoint of the two objects; ``next_to``, the middle of the band on the side the
object comes from; a region, :data:`REGION_DEPTH_M` into it from the middle of the table's working area.
"""

from __future__ import annotations

import numpy as np

from gendex_envs.conditions import CONDITION_DEFAULTS, ConditionSpec
from gendex_envs.holds import holds_box, holds_point, in_holds
from gendex_envs.success import REGION_AHEAD_M, REGION_DEPTH_M, REGION_PARTS, rest_point, robot_axes

POINT_CARRY_M = 0.05
"""A carry to a table point with no object to clear (a region of the table) brings the held object's bottom this far
(+ the carry clearance) over the table top."""
POINT = "<point>"
"""What :attr:`gendex.solve.rigid.RigidPrimitives.placed_on` says after a place at a table point."""


def placed_condition(env, held: str, stage=None) -> ConditionSpec | None:
    """The ``placed`` condition on ``held`` (the stage's first, then the task's), if any."""
    conds = (*((stage.success or ()) if stage is not None else ()), *env.task_spec.success.conditions)
    return next((c for c in conds if c.type == "placed" and c.object == held and not c.negate), None)


def holds_condition(env, held: str, stage=None) -> ConditionSpec | None:
    """The ``inside`` condition on ``held`` with a joint (*put the can in the drawer*; the stage's first, then the
    task's), if any."""
    conds = (*((stage.success or ()) if stage is not None else ()), *env.task_spec.success.conditions)
    return next((c for c in conds if c.type == "inside" and c.object == held and c.joint is not None
                 and not c.negate), None)


def holds_spot(env, c: ConditionSpec) -> np.ndarray:
    """[3] the world point to set ``c.object`` down at for ``c`` (an ``inside`` condition with a joint): the middle
    of the floor of the drawer's bin, from the first env's state."""
    return holds_point(env, c.target, c.joint)[0].double().cpu().numpy()


DRAWER_SIDE_M = 0.1
"""An object taken out of a drawer is set down this far beyond the drawer's side wall (centre)."""


def drawer_of(env, name: str, chest: str) -> str | None:
    """The joint of ``chest``'s drawer whose bin object ``name`` lay in at reset (first env), if any."""
    if chest not in env.articulations:
        return None
    point = env.init_obj_pos(name)
    for j in env.asset_record(chest).joints:
        if j.holds_m is not None and bool(in_holds(env, chest, j.name, point)[0]):
            return j.name
    return None


def drawer_side(env, chest: str, joint: str, base: np.ndarray, left: np.ndarray) -> np.ndarray:
    """[2] the table point beside ``chest``'s slid-out drawer ``joint`` (:data:`DRAWER_SIDE_M` beyond its side wall,
    level with the middle of its part out of the chest), on the side towards the robot's middle."""
    middle = holds_point(env, chest, joint)[0, :2].double().cpu().numpy()
    lo, hi = holds_box(env, chest, joint)
    q = env.obj_pose(chest).q[0].double().cpu().numpy()
    yaw = 2.0 * np.arctan2(q[3], q[0])
    across = np.array([-np.sin(yaw), np.cos(yaw)])  # the chest's +y
    side = -float(np.sign(np.dot(middle - base, left))) or 1.0
    across = across * (side if np.dot(across, left) >= 0 else -side)
    return middle + (float(hi[1] - lo[1]) / 2 + DRAWER_SIDE_M) * across


def holds_height(env, c: ConditionSpec) -> float:
    """How high the walls of the drawer's bin of ``c`` (an ``inside`` condition with a joint) stand over its floor."""
    lo, hi = holds_box(env, c.target, c.joint)
    return float(hi[2] - lo[2])


def set_down_point(env, c: ConditionSpec) -> np.ndarray:
    """[2] the table point (world xy) to set ``c.object`` down at so that ``c`` holds, from the first env's state."""
    def xy(name: str) -> np.ndarray:
        return rest_point(env, name)[0, :2].double().cpu().numpy()

    p = xy(c.object)
    base, fwd, left = (t.double().cpu().numpy() for t in robot_axes(env, rest_point(env, c.object)))
    if c.relation == "in_region":
        point = base + REGION_AHEAD_M * fwd
        for part in ("centre",) if c.region == "centre" else c.region.split("_"):
            if part != "centre":
                axis, sign = REGION_PARTS[part]
                point = point + sign * REGION_DEPTH_M * (fwd, left)[axis]
        return point
    a = xy(c.target)
    if c.relation == "between":
        return (a + xy(c.other)) / 2
    lo, hi = (CONDITION_DEFAULTS[k] if getattr(c, k) is None else getattr(c, k) for k in ("min_gap_m", "max_gap_m"))
    gap = (lo + hi) / 2
    if c.relation == "next_to":
        out = drawer_of(env, c.object, c.target)
        if out is not None:  # out of a chest's drawer: beside the drawer, towards the middle of the robot's reach
            return drawer_side(env, c.target, out, base, left)
        d = p - a
        n = float(np.linalg.norm(d))
        if n >= lo:  # beside it already, out of the band: set down on the side it comes from
            return a + gap * d / n
        # it starts in or against the target (taken out of a bowl): sideways, towards the middle of the robot's reach
        side = -float(np.sign(np.dot(a - base, left))) or 1.0
        return a + gap * side * left
    axis = {"left_of": left, "right_of": -left, "behind": fwd, "in_front_of": -fwd}[c.relation]
    return a + gap * axis


SLOT_NEAR_SHARE = 0.6
"""On a plate, tray or board that is to hold several objects (``near`` conditions), the slots lie this share of the
conditions' ``max_dist_m`` from its middle (well within what they accept: the rest point may sit off the slot)."""


def free_spot(env, container: str, held: str) -> np.ndarray | None:
    """[2] where on or in ``container`` to set ``held`` down when it is to hold several objects (*put all the fruit
    in the pot*, *set the two blocks on the tray*: every ``inside`` or ``near`` condition of the task on it) or, a
    container, others already lie in it. The first of several goes to the robot's left, as far from the middle as
    it stays within what an ``inside`` condition checks (on a surface: :data:`SLOT_NEAR_SHARE` of
    ``max_dist_m``), so the next have room; each next one to the free slot of as many evenly round the middle,
    turned to where the first came to rest (round objects roll: where they lie counts, not where they were set
    down), farthest from what lies there. None when ``container`` is to hold only ``held`` and holds nothing
    else."""
    conds = [x for x in env.task_spec.success.conditions if x.target == container and not x.negate
             and ((x.type == "inside" and x.joint is None) or x.type == "near")]
    near = next((x for x in conds if x.object == held and x.type == "near"), None)
    radius = SLOT_NEAR_SHARE * float(near.max_dist_m) if near else env.container_extent(container)[0]
    c = rest_point(env, container)[0, :2].double().cpu().numpy()
    size = np.asarray(env.asset_record(held).size_m[:2]) * env.task_spec.object(held).scale
    room = max(0.0, radius - (0.0 if near else 0.5 * float(np.max(size))))
    peers = [x.object for x in conds]
    reach = 0.5 * float(np.max(env.asset_record(container).size_m[:2])) * env.task_spec.object(container).scale
    lying = []  # what lies anywhere on or in it (a ball set down on a tray may roll to its edge)
    for name in env.objects:
        if name in (container, held) or name in env.articulations:
            continue
        xy = rest_point(env, name)[0, :2].double().cpu().numpy()
        if float(np.linalg.norm(xy - c)) < reach:
            lying.append(xy)
    several = held in peers and len(set(peers)) > 1
    if not lying:
        if not several:
            return None
        return c + room * robot_axes(env, rest_point(env, container))[2].double().cpu().numpy()
    if near is not None and not several:
        return None
    # the slots evenly round the middle, turned to where the first object came to rest: the free one farthest
    # from what lies there (two: across from it, three: 120 degrees on)
    n = max(len(set(peers)) if several else 0, len(lying) + 1)
    d = lying[0] - c
    start = float(np.arctan2(d[1], d[0])) if float(np.linalg.norm(d)) > 1e-3 else 0.0
    turns = start + 2.0 * np.pi * np.arange(n) / n
    slots = [c + room * np.array([np.cos(t), np.sin(t)]) for t in turns]
    return max(slots, key=lambda p: min(float(np.linalg.norm(p - q)) for q in lying))


__all__ = ["DRAWER_SIDE_M", "POINT", "POINT_CARRY_M", "REGION_DEPTH_M", "SLOT_NEAR_SHARE", "drawer_of", "drawer_side",
           "free_spot", "holds_condition", "holds_height", "holds_spot", "placed_condition", "set_down_point"]
