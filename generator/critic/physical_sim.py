"""The critic's physical checks in the simulator: :func:`check_scene`.

It builds the scene in SAPIEN (CPU, randomization off, the robot at the spec's initial keyframe: ``rest`` unless
the spec says otherwise; both keyframes share the same arm pose), replaces the bounding-box penetration estimate of
:func:`~generator.critic.physical.check_scene_static` with PhysX's own contacts at reset, then lets the scene
settle and measures what fell or still moves (the ``penetration`` and ``floating`` checks described in
:mod:`generator.critic.physical`). The robot at rest is also measured against every randomized object at the
extremes of its randomization (:func:`_draw_checks`, in the same env), where a draw can turn a peg or a door into
the hand. A scene whose fixed structures leave no room (the ``structure_room`` check) is not built: the env may
refuse it, and it must change first. About 0.3 s per scene once SAPIEN is loaded, the extremes 0.08 s of it (the
first env of a process costs ~3 s of imports).
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from gendex_envs.physx import px_objects
from gendex_envs.spec import RandomizeSpec, TaskSpec
from generator.critic.directives import Directive
from generator.critic.layout import PENETRATION_FIX_MARGIN_M, separating_move
from generator.critic.physical import (
    FALL_TOL_M,
    MOVING_TOL_MPS,
    PENETRATION_TOL_M,
    SETTLE_STEPS,
    PhysicalReport,
    Placed,
    Violation,
    log,
    moves,
    ordered,
    penetration_fix,
    pick_mover,
    randomization_xy,
    rounded,
    static_findings,
)

EXTREMES = tuple((sx, sy, turn) for sx in (-1, 1) for sy in (-1, 1) for turn in (-1, 0, 1))
"""The randomization extremes the robot at rest is measured against: (x, y) corner of the xy range, yaw end."""
MAX_DRAW_FIX_M = 0.05
"""Longest move (m) one fix of a randomized draw's penetration asks for (the next round measures again)."""


def _without_randomization(spec: TaskSpec) -> TaskSpec:
    objects = tuple(dataclasses.replace(o, randomize=RandomizeSpec()) for o in spec.objects)
    return dataclasses.replace(spec, objects=objects)


def _contact_penetrations(env, spec: TaskSpec, placed: dict[str, Placed], boxes: dict[str, tuple],
                          start: dict[str, np.ndarray], meas: dict) -> list[Violation]:
    """Penetrations in PhysX's contact list (one per object pair; one per object for the table and the robot)."""
    from gendex_envs.reset_contacts import entity_ids

    owner: dict[int, str] = {i: name for name, entity in env.objects.items() for i in entity_ids(entity)}
    robot_links = {px_objects(link)[0].entity.per_scene_id: link for link in env.agent.robot.get_links()}
    table_id = px_objects(env.table)[0].per_scene_id
    pairs: dict[tuple[str, str], float] = {}  # (object, object) sorted, or (object, "table")
    robot: dict[str, dict[str, float]] = {}  # object -> robot link -> depth
    for c in env.scene.px.get_contacts():
        ids = [b.entity.per_scene_id for b in c.bodies]
        a, b = (owner.get(i) for i in ids)
        if a == b or any(n is not None and n not in placed for n in (a, b)):
            continue  # inside one articulation, neither is an object, or a piece laid in a vessel
        if a is None:  # keep the object first
            a, b, ids = b, a, ids[::-1]
        depth = -min(p.separation for p in c.points)
        if b is None and ids[1] in robot_links:
            links = robot.setdefault(a, {})
            name = robot_links[ids[1]].name
            links[name] = max(links.get(name, 0.0), depth)
            continue
        if b is None and ids[1] != table_id:
            continue  # the ground, the goal site
        key = (a, "table") if b is None else tuple(sorted((a, b)))
        pairs[key] = max(pairs.get(key, 0.0), depth)
    meas["_method"] = "PhysX contact separations after one physics step from the reset state"
    violations: list[Violation] = []
    for (a, b), depth in sorted(pairs.items()):
        meas.setdefault(a, {})[b] = rounded(depth)
        if depth <= PENETRATION_TOL_M:
            continue
        if b == "table":
            violations.append(Violation(
                "penetration", a, f"{a!r} sinks {depth:.3f} m into the table at reset", measured=depth,
                limit=PENETRATION_TOL_M, fix=(Directive.move(a, "z", math.ceil((depth + 0.002) * 1000) / 1000),),
                other="table"))
            continue
        pm, po = pick_mover(placed[a], placed[b])
        fix = penetration_fix(spec, placed, pm, po, boxes[pm.spec.name], boxes[po.spec.name])
        violations.append(Violation(
            "penetration", pm.spec.name, f"{a!r} and {b!r} interpenetrate by {depth:.3f} m at reset",
            measured=depth, limit=PENETRATION_TOL_M, fix=fix, other=po.spec.name))
    for a, links in sorted(robot.items()):
        meas.setdefault(a, {}).update({f"robot:{k}": rounded(v) for k, v in links.items()})
        violation = _robot_violation(env, a, links, boxes[a], float(start[a][1]), placed[a])
        if violation is not None:
            violations.append(violation)
    return violations


def _robot_violation(env, name: str, links: dict[str, float], box: tuple, start_y: float, placed: Placed
                     ) -> Violation | None:
    """The penetration of ``name`` by the robot at rest (``links``: link -> depth), if deeper than tolerated, with
    one fix for the whole robot: out of the xy footprint of every robot link that reaches down below the object's
    top (moving away from one finger would push it into the next)."""
    from gendex_envs.assets.bounds import body_points

    deep = {k: v for k, v in links.items() if v > PENETRATION_TOL_M}
    if not deep:
        return None
    lo, hi = box
    bodies = [px_objects(link)[0] for link in env.agent.robot.get_links()]
    pts = [body_points(b.entity_pose, b.collision_shapes) for b in bodies]
    low = [p for p in pts if len(p) and p[:, 2].min() < hi[2] + PENETRATION_FIX_MARGIN_M]
    obstacle = np.concatenate(low)
    fix = moves(name, separating_move(lo, hi, obstacle.min(axis=0), obstacle.max(axis=0), start_y,
                                      randomization_xy(placed)))
    worst = max(deep, key=deep.get)
    return Violation(
        "penetration", name, f"{name!r} and the robot interpenetrate at reset, by {deep[worst]:.3f} m at its "
        f"{worst} ({len(deep)} link{'s' if len(deep) > 1 else ''}: {', '.join(sorted(deep))}); the robot stands "
        "at its initial keyframe", measured=deep[worst], limit=PENETRATION_TOL_M, fix=fix, other=f"robot:{worst}")


def _draw_checks(env, spec: TaskSpec, seed: int, placed: dict[str, Placed], meas: dict) -> list[Violation]:
    """The robot at rest against the objects at the extremes of their randomization (the nominal layout can be
    clear while a shift or yaw draw swings a peg or a door into the hand): every randomized object shifted to each
    corner of its xy range, turned to either end of its yaw range and not turned (:data:`EXTREMES`), the others
    nominal. One violation per object, from its deepest extreme; its fix moves the object away from the palm
    (horizontally, from the palm to the object's origin there) by the depth plus the fix margin, at most
    :data:`MAX_DRAW_FIX_M` (the next round measures again). ``env``: the critic's env of the nominal layout, reset
    for each extreme."""
    import torch
    from mani_skill.utils.structs.pose import Pose

    from gendex_envs.geometry import quat_mul, yaw_quat
    from gendex_envs.reset_contacts import robot_penetrations

    moving = [o for o in spec.objects if o.name in placed and (any(o.randomize.xy_m) or o.randomize.yaw_deg)]
    worst: dict[str, tuple[str, object, np.ndarray]] = {}  # object -> (extreme, deepest Penetration, away from palm)
    for sx, sy, turn in EXTREMES if moving else ():
        env.reset(seed=seed)
        for o in moving:
            entity = env.objects[o.name]
            p, q = entity.pose.p.clone(), entity.pose.q.clone()
            p[:, 0] += sx * o.randomize.xy_m[0]
            p[:, 1] += sy * o.randomize.xy_m[1]
            q = quat_mul(yaw_quat(torch.full((1,), turn * math.radians(o.randomize.yaw_deg))), q)
            entity.set_pose(Pose.create_from_pq(p, q))
        env.scene.step()
        palm = env.agent.palm_link.pose.p[0, :2].numpy()
        for name, links in robot_penetrations(env).items():
            deepest = max(links.values(), key=lambda p: p.depth)
            if name in placed and deepest.depth > PENETRATION_TOL_M and \
                    deepest.depth > getattr(worst.get(name, ("", None))[1], "depth", 0.0):
                where = f"shifted ({sx:+d}, {sy:+d}) x its xy range, turned {turn:+d} x its yaw range"
                worst[name] = (where, deepest, env.objects[name].pose.p[0, :2].numpy() - palm)
    violations = []
    for name, (where, pen, away) in sorted(worst.items()):
        meas.setdefault(name, {})["robot@extreme"] = rounded(pen.depth)
        size = float(np.linalg.norm(away))
        direction = away / size if size > 1e-6 else np.array([1.0, 0.0])
        step = min(pen.depth + PENETRATION_FIX_MARGIN_M, MAX_DRAW_FIX_M)
        violations.append(Violation(
            "penetration", name, f"{name!r} and the robot interpenetrate by {pen.depth:.3f} m at its {pen.link} "
            f"when {name!r} is {where} (a randomized reset can draw it); the robot stands at its initial keyframe",
            measured=pen.depth, limit=PENETRATION_TOL_M, fix=moves(name, direction * step), other=f"robot:{pen.link}"))
    return violations


def _sim_checks(spec: TaskSpec, seed: int, settle_steps: int, placed: dict[str, Placed],
                unsupported_fix: dict[str, tuple], off_table: set[str], meas: dict) -> list[Violation]:
    from gendex_envs.assets.bounds import entity_aabb
    from gendex_envs.task_env import TaskEnv

    env = TaskEnv(task_spec=_without_randomization(spec), render_backend="none", control_mode="pd_joint_delta_pos")
    try:
        env.reset(seed=seed)
        start = {n: e.pose.p[0].numpy().copy() for n, e in env.objects.items()}
        boxes = {n: entity_aabb(e) for n, e in env.objects.items()}

        env.scene.step()  # one physics step: PhysX lists the contacts of the reset state
        violations = _contact_penetrations(env, spec, placed, boxes, start, meas["penetration"])

        zero = np.zeros(env.action_space.shape, dtype=np.float32)
        for _ in range(max(settle_steps - 1, 0)):
            env.step(zero)
        before = {n: e.pose.p[0].numpy().copy() for n, e in env.objects.items()}
        env.step(zero)
        dt = 1.0 / env.control_freq
        flo = meas["floating"]
        flo["_method"] = (f"pose change over {settle_steps} control steps ({settle_steps * dt:.2f} s), "
                          "robot holding still")
        for name, entity in env.objects.items():
            end = entity.pose.p[0].numpy()
            drop = float(start[name][2] - end[2])
            speed = float(np.linalg.norm(end - before[name]) / dt)
            flo[name] = {"drop_m": rounded(drop), "speed_mps": rounded(speed),
                         "moved_m": rounded(float(np.linalg.norm(end - start[name])))}
            if spec.object(name).fixed or name in off_table or name not in placed:
                continue
            if drop > FALL_TOL_M:
                fix = unsupported_fix.get(name) or (Directive.move(name, "z", -math.floor((drop - 0.002) * 1000)
                                                                   / 1000),)
                violations.append(Violation(
                    "floating", name, f"{name!r} fell {drop:.3f} m while the scene settled: it was placed above "
                    f"what supports it", measured=drop, limit=FALL_TOL_M, fix=fix))
            elif speed > MOVING_TOL_MPS:
                violations.append(Violation(
                    "floating", name, f"{name!r} still moves at {speed:.3f} m/s after the scene settled for "
                    f"{settle_steps * dt:.2f} s: it does not rest stably", measured=speed, limit=MOVING_TOL_MPS))
        if not any(v.check == "penetration" and str(v.other).startswith("robot:") for v in violations):
            violations += _draw_checks(env, spec, seed, placed, meas["penetration"])
        return violations
    finally:
        env.close()


def check_scene(spec: TaskSpec, *, seed: int = 0, settle_steps: int = SETTLE_STEPS) -> PhysicalReport:
    """All checks, penetration and floating measured in the simulator (module docstring)."""
    if settle_steps < 1:
        raise ValueError(f"settle_steps={settle_steps} must be >= 1")
    t0 = time.perf_counter()
    violations, meas, placed, unsupported_fix = static_findings(spec, overlap=False)
    off = {v.object for v in violations if v.check == "off_table"}
    if any(v.check == "structure_room" for v in violations):  # the scene must change first (the env may refuse it)
        log.info("physical check of %s: a scene structure leaves no room; not built in the simulator", spec.name)
    else:
        violations += _sim_checks(spec, seed, settle_steps, placed, unsupported_fix, off, meas)
    report = PhysicalReport(spec.name, "sim", ordered(violations), meas, time.perf_counter() - t0)
    log.info("physical check of %s: %d violations in %.2f s", spec.name, len(report.violations), report.seconds)
    return report
