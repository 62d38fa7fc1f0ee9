"""The arm's motion planner sees a scene's fixed structures: their boxes are static obstacles of the collision model
(gendex.solve.collision), so a planned motion goes round a structure in its way or is refused, never through it.

The planner runs on the robot's own kinematics (SAPIEN's Pinocchio model of the generated URDF, loaded without an
env), against structures placed by gendex_envs.scene_geometry, as an env of a task with a scene has them."""

from __future__ import annotations

import numpy as np
import pytest
import sapien

from gendex.solve.collision import ArmCollisionModel, Box, structure_obstacles
from gendex.solve.ik import ArmIK
from gendex.solve.motion import scene_obstacles
from gendex.solve.planner import ArmPlanner, PlanningError
from gendex_envs.agents import robot_model as rm
from gendex_envs.agents.ur10e_shadow import ARM_JOINTS, KEYFRAME_QPOS_BY_NAME
from gendex_envs.scene import place_structures
from gendex_envs.scene_geometry import structure_boxes
from gendex_envs.scene_spec import StructureSpec, resolve_scene
from gendex_envs.scene_styles import STYLES
from gendex_envs.spec import RobotSpec, TableSpec

TABLE = TableSpec()


@pytest.fixture(scope="module")
def ik() -> ArmIK:
    """IK/FK of the UR10e + ShadowHand at the spec's default base, from the URDF alone (no ManiSkill env)."""
    scene = sapien.Scene()
    loader = scene.create_urdf_loader()
    loader.fix_root_link = True
    robot = loader.load(str(rm.robot_urdf_path()))
    out = ArmIK.__new__(ArmIK)
    out.model = robot.create_pinocchio_model()
    out.joint_names = [j.name for j in robot.get_active_joints()]
    out.link_names = [link.name for link in robot.get_links()]
    out.arm = np.array([out.joint_names.index(n) for n in ARM_JOINTS])
    out.mask = np.zeros(len(out.joint_names), dtype=np.int32)
    out.mask[out.arm] = 1
    out.limits = np.asarray(robot.get_qlimits(), dtype=np.float64)
    out.base = sapien.Pose(list(RobotSpec().base_pos_m))
    return out


@pytest.fixture(scope="module")
def rest(ik) -> np.ndarray:
    return np.array([KEYFRAME_QPOS_BY_NAME["rest"][n] for n in ik.joint_names], dtype=np.float64)


def _palm_at(ik: ArmIK, rest: np.ndarray, p) -> np.ndarray:
    q = ik.solve(sapien.Pose(p, ik.fk(rest).q), rest)  # palm turned down as at rest
    assert q is not None, p
    return q


def _wall(kind: str, x: float, yaw: float = 90.0) -> list[Box]:
    return structure_obstacles(structure_boxes([StructureSpec(name="wall", kind=kind, pos_m=(x, 0.0, 0.0),
                                                              yaw_deg=yaw)], TABLE))


def test_a_planned_motion_goes_over_a_structure_in_its_way(ik, rest):
    """The palm moves 15 cm above the table from y = +0.3 to y = -0.3. Free, the straight joint-space motion is the
    plan; with a 60 cm splashback standing across the table between the two ends, that motion is blocked, and the
    plan that comes back keeps every step clear of it (and of the table), lifting the arm over it."""
    col = ArmCollisionModel(ik)
    planner = ArmPlanner(col)
    a, b = _palm_at(ik, rest, [0.0, 0.3, 0.15]), _palm_at(ik, rest, [0.0, -0.3, 0.15])
    assert planner.segment_free(a, b)
    straight = planner.plan(a, b)
    top = max(float(col.sphere_centres(q)[0][:, 2].max()) for q in straight)

    col.set_static(_wall("backsplash", 0.6))  # 1.6 m long along x (x -0.2..1.4), 2 cm thick at y = 0, 0.6 m tall
    assert col.static and not planner.segment_free(a, b)
    assert col.is_free(a) and col.is_free(b)
    path = planner.plan(a, b)
    q_prev = a
    for q in path:  # every waypoint, and the straight segment from the one before, clear of the wall
        assert col.clearance(q) >= 0.0
        assert planner.segment_free(q_prev, q)
        q_prev = q
    np.testing.assert_allclose(path[-1][ik.arm], b[ik.arm])
    assert max(float(col.sphere_centres(q)[0][:, 2].max()) for q in path) > max(top, 0.6)


def test_a_goal_inside_a_structure_is_refused(ik, rest):
    """A filing cabinet (1 m tall) standing where the palm is to go: the planner refuses, it does not plan into it."""
    col = ArmCollisionModel(ik)
    planner = ArmPlanner(col)
    a, b = _palm_at(ik, rest, [0.0, 0.3, 0.15]), _palm_at(ik, rest, [0.0, -0.3, 0.15])
    col.set_static(structure_obstacles(structure_boxes(
        [StructureSpec(name="cabinet", kind="filing_cabinet", pos_m=(0.0, -0.3, 0.0))], TABLE)))
    with pytest.raises(PlanningError, match="goal configuration in collision"):
        planner.plan(a, b)


def test_static_obstacles_stay_whatever_a_primitive_sets(ik, rest):
    """A primitive sets the objects it avoids before each motion (set_obstacles); the structures stay."""
    col = ArmCollisionModel(ik)
    walls = _wall("backsplash", 0.6)
    col.set_static(walls)
    col.set_obstacles([Box(np.array([0.5, 0.5, 0.0]), np.array([0.6, 0.6, 0.1]), "apple")])
    col.set_obstacles([])
    assert col.static == walls
    a, b = _palm_at(ik, rest, [0.0, 0.3, 0.15]), _palm_at(ik, rest, [0.0, -0.3, 0.15])
    assert not ArmPlanner(col).segment_free(a, b)


def test_every_style_leaves_the_arm_free_over_the_table(ik, rest):
    """The styles stand their structures beside the table: the rest pose and palm-down poses over the whole table
    (10 and 30 cm up) stay as free with each style's structures as without them."""
    col = ArmCollisionModel(ik)
    poses = [q for x in (-0.3, 0.0, 0.3) for y in (-0.5, 0.0, 0.5) for z in (0.1, 0.3)
             if (q := ik.solve(sapien.Pose([x, y, z], ik.fk(rest).q), rest)) is not None and col.is_free(q)]
    assert len(poses) >= 15  # of 18: the two nearest the base at its sides have no palm-down IK
    for name, style in STYLES.items():
        col.set_static(structure_obstacles(structure_boxes(style.structures, TABLE)))
        assert len(col.static) >= (1 if style.structures else 0), name
        assert col.is_free(rest), name
        assert all(col.is_free(q) for q in poses), name


def test_the_planner_places_structures_where_the_env_builds_them():
    """scene_geometry's boxes and the env's placement (gendex_envs.scene) agree: same poses, same world bounds."""
    for name, style in STYLES.items():
        boxes = structure_boxes(style.structures, TABLE, collision_only=False)
        for ps in place_structures(style.structures, TABLE):
            mine = [b for b in boxes if b.structure == ps.spec.name]
            lo, hi = ps.world_bounds()
            np.testing.assert_allclose(np.min([b.lo for b in mine], axis=0), lo, atol=1e-5, err_msg=name)
            np.testing.assert_allclose(np.max([b.hi for b in mine], axis=0), hi, atol=1e-5, err_msg=name)
            for b, pose in zip(mine, ps.part_poses(), strict=True):
                np.testing.assert_allclose(b.pose[:3, 3], pose.p, atol=1e-5)


def test_an_env_with_a_scene_gives_its_planner_the_structures():
    """ArmHandMotion's static obstacles come from the env's scenery (its task's scene or the env's scene=)."""

    class _Scenery:
        scene = resolve_scene(STYLES["kitchen"])

    class _Spec:
        table = TABLE

    class _Env:
        scenery = _Scenery()
        task_spec = _Spec()

    boxes = scene_obstacles(_Env())
    assert {b.name for b in boxes} == {f"structure:{s.name}" for s in STYLES["kitchen"].structures}
    _Env.scenery = None
    assert scene_obstacles(_Env()) == []


def test_a_search_ends_on_counted_checks_not_on_the_clock(ik, rest, monkeypatch):
    """The search over the splashback, planned twice with the same seed: once as is, once with every collision check
    slowed down (a loaded machine). The budget counts checks, so both plans are the same, waypoint for waypoint; a
    budget below what the search needs fails, saying so (a wall-clock budget had made dataset builds differ with
    the machine's load)."""
    import time

    col = ArmCollisionModel(ik)
    col.set_static(_wall("backsplash", 0.6))
    a, b = _palm_at(ik, rest, [0.0, 0.3, 0.15]), _palm_at(ik, rest, [0.0, -0.3, 0.15])
    fast = ArmPlanner(col, seed=7)
    first = fast.plan(a, b)
    needed = fast.last_checks
    assert 0 < needed < fast.max_checks

    slow = ArmPlanner(col, seed=7)
    check = slow._ok
    monkeypatch.setattr(slow, "_ok", lambda q, floor: (time.sleep(2e-4), check(q, floor))[1])
    np.testing.assert_array_equal(slow.plan(a, b), first)
    assert slow.last_checks == needed

    short = ArmPlanner(col, seed=7, max_checks=max(1, needed // 4))
    with pytest.raises(PlanningError, match=f"in {max(1, needed // 4)} collision checks"):
        short.plan(a, b)
    with pytest.raises(ValueError, match="max_checks 0 must be a positive number"):
        ArmPlanner(col, max_checks=0)
