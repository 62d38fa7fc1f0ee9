"""Every catalog asset in the simulator: it rests, its size is what the catalog says, containers hold, joints move,
handles are reachable by the robot. Assets are tested many at a time in one scene (one env build)."""

import math

import numpy as np
import pytest
import sapien
import torch

from gendex_envs.assets.bounds import entity_aabb
from gendex_envs.assets.catalog import THIN_M, THIN_SOLVER_ITERATIONS, catalog
from gendex_envs.physx import px_bodies, px_objects
from gendex_envs.spec import parse_task_spec
from gendex_envs.task_env import TaskEnv
from gendex_envs.typed_yaml import MAX_OBJECTS

RIGID = sorted(r.id for r in catalog().values() if not r.articulated)
ARTICULATED = sorted(r.id for r in catalog().values() if r.articulated)
CONTAINERS = sorted(r.id for r in catalog().values() if not r.articulated and "container" in r.tags
                    and r.category not in ("bottle", "can", "box"))
SPACING_M = 0.3
REACH_TEST_X = 0.45
"""Where the reachability test puts each articulated asset (x of its footprint centre, m)."""
PALM_FACING_X = np.column_stack([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
"""Palm frame axes (x, y, z) in the world when the palm faces +x with the fingers up."""


def _grid_spec(objects: list[dict], table_m: float) -> dict:
    return parse_task_spec({
        "name": "AssetCheck", "instruction": "Check assets.",
        "table": {"size_m": [table_m, table_m]},
        "objects": objects,
        "stages": [{"name": "idle", "instruction": "Idle.", "skill": "reorient", "method": "RL",
                    "control_joint": "hand"}],
        "success": {"description": "never", "conditions": [{"type": "lifted", "object": objects[0]["name"],
                                                             "min_height_m": 10.0}]},
    }, source="<test_assets>")


def _grid_positions(n: int, spacing: float, start_x: float = 0.45) -> list[tuple[float, float]]:
    side = math.ceil(math.sqrt(n))
    # start in front of the robot's hand so nothing touches the arm
    return [(start_x + spacing * (i // side), spacing * (i % side - (side - 1) / 2)) for i in range(n)]


def _make(objects: list[dict], spacing: float = SPACING_M) -> TaskEnv:
    far = max(abs(o["pos_m"][0]) for o in objects) + spacing
    far = max(far, max(abs(o["pos_m"][1]) for o in objects) + spacing)
    env = TaskEnv(task_spec=_grid_spec(objects, 2 * far + 1.0), render_backend="none")
    env.reset(seed=0)
    return env


def _idle(env: TaskEnv, seconds: float) -> None:
    for _ in range(int(seconds * 120)):
        env.scene.step()


@pytest.fixture(scope="module")
def rigid_scene():
    """Every rigid asset on a grid, idled 2 s, in as many scenes as MAX_OBJECTS allows: asset id -> (env, its pose
    before idling by object name)."""
    envs, where = [], {}
    for at in range(0, len(RIGID), MAX_OBJECTS):
        chunk = RIGID[at:at + MAX_OBJECTS]
        objs = [{"name": f"a_{aid}", "asset": aid, "pos_m": [x, y, 0.0]}
                for aid, (x, y) in zip(chunk, _grid_positions(len(chunk), SPACING_M), strict=True)]
        env = _make(objs)
        envs.append(env)
        start = {o["name"]: env.obj(o["name"]).pose.raw_pose[0].clone() for o in objs}
        _idle(env, 2.0)
        where.update({aid: (env, start) for aid in chunk})
    yield where
    for env in envs:
        env.close()


def test_catalog_is_large_enough():
    assert len(RIGID) >= 40
    categories = {}
    for aid in ARTICULATED:
        categories.setdefault(catalog()[aid].category, []).append(aid)
    assert len(categories) >= 10, categories
    assert all(len(v) >= 2 for v in categories.values()), categories


@pytest.mark.parametrize("asset_id", RIGID)
def test_rigid_asset_rests_on_table(rigid_scene, asset_id):
    env, start = rigid_scene[asset_id]
    name = f"a_{asset_id}"
    pose = env.obj(name).pose.raw_pose[0]
    assert torch.isfinite(pose).all()
    drift = torch.linalg.norm(pose[:3] - start[name][:3]).item()
    assert drift < 0.01, f"{asset_id} drifted {100 * drift:.1f} cm in 2 s"
    lo, _ = entity_aabb(env.obj(name))
    assert lo[2] > -0.004, f"{asset_id} sank {1000 * -lo[2]:.1f} mm into the table"
    assert lo[2] < 0.004, f"{asset_id} floats {1000 * lo[2]:.1f} mm above the table"


def test_only_thin_objects_get_more_contact_solver_iterations(rigid_scene):
    """A knife, a spoon or a fork is solved at THIN_SOLVER_ITERATIONS, everything else at the scene's 15."""
    got = {aid: px_bodies(rigid_scene[aid][0].obj(f"a_{aid}"))[0].solver_position_iterations for aid in RIGID}
    thin = {aid for aid in RIGID if min(catalog()[aid].size_m) < THIN_M}
    assert {"knife", "spoon", "fork", "scissors"} <= thin and not {"apple", "dice", "plate", "marker"} & thin
    assert {aid for aid, n in got.items() if n == THIN_SOLVER_ITERATIONS} == thin
    assert {n for aid, n in got.items() if aid not in thin} == {15}
    robot = px_objects(rigid_scene[RIGID[0]][0].agent.robot)[0]
    assert robot.solver_position_iterations == 15
    knife = catalog()["knife"]
    assert knife.solver_position_iterations(1.0) == THIN_SOLVER_ITERATIONS
    assert knife.solver_position_iterations(1.5) is None  # an 18 mm-thick knife is not thin


@pytest.mark.parametrize("asset_id", RIGID)
def test_rigid_asset_size_matches_catalog(rigid_scene, asset_id):
    env, _ = rigid_scene[asset_id]
    lo, hi = entity_aabb(env.obj(f"a_{asset_id}"))
    record = catalog()[asset_id]
    expected = np.asarray(record.size_m)
    # yaw-free rest: compare sorted horizontal extents (a resting object may turn about z) and the height
    got = np.array([*sorted((hi - lo)[:2]), (hi - lo)[2]])
    want = np.array([*sorted(expected[:2]), expected[2]])
    np.testing.assert_allclose(got, want, rtol=0.10, err_msg=asset_id)


def test_containers_hold_a_dropped_ball():
    """A golf ball dropped into the middle of each container comes to rest inside it."""
    assert CONTAINERS, "the catalog has no open containers"
    positions = _grid_positions(len(CONTAINERS), 0.35)
    objs = []
    for aid, (x, y) in zip(CONTAINERS, positions, strict=True):
        height = catalog()[aid].size_m[2]
        objs.append({"name": f"c_{aid}", "asset": aid, "pos_m": [x, y, 0.0]})
        objs.append({"name": f"b_{aid}", "asset": "golf_ball", "pos_m": [x, y, height + 0.03]})
    env = _make(objs, 0.35)
    try:
        _idle(env, 2.0)
        escaped = []
        for aid in CONTAINERS:
            c_lo, c_hi = entity_aabb(env.obj(f"c_{aid}"))
            ball = env.obj(f"b_{aid}").pose.p[0].numpy()
            inside = np.all(ball[:2] > c_lo[:2]) and np.all(ball[:2] < c_hi[:2]) and ball[2] < c_hi[2]
            if not inside:
                escaped.append((aid, ball.round(3).tolist()))
        assert not escaped, f"the ball did not stay in: {escaped}"
    finally:
        env.close()


@pytest.fixture(scope="module")
def articulated_scene():
    objs = [{"name": f"j_{aid}", "asset": aid, "pos_m": [x, y, 0.0], "fixed": True}
            for aid, (x, y) in zip(ARTICULATED, _grid_positions(len(ARTICULATED), 1.0, start_x=1.2), strict=True)]
    env = _make(objs, 1.0)
    yield env
    env.close()


@pytest.mark.parametrize("asset_id", ARTICULATED)
def test_articulated_joints_move_through_their_limits(articulated_scene, asset_id):
    env = articulated_scene
    art = env.articulations[f"j_{asset_id}"]
    joints = art.get_active_joints()
    springs = {j.name: j.spring for j in catalog()[asset_id].joints if j.spring}
    for j in joints:  # a button's own spring (a 20 g cap sags 1 mm, 8 % of its travel, on 200 N/m)
        k = springs.get(j.name, 200.0)
        j.set_drive_properties(stiffness=k, damping=0.1 * k, force_limit=200.0)
    limits = art.get_qlimits()[0]
    span = (limits[:, 1] - limits[:, 0]).clamp(min=1e-6)
    order = list(range(len(joints)))
    # open one joint after the other, then close them in reverse (a rack slides out only once the door is open)
    for end, sequence in ((1, order), (0, order[::-1])):
        for i in sequence:
            joints[i].set_drive_target(float(limits[i, end]))
            _idle(env, 1.5)
            q = art.get_qpos()[0]
            err = (q[i] - limits[i, end]).abs().item() / span[i].item()
            assert err < 0.05, f"{asset_id}: joint {joints[i].name} at {q[i]:.3f}, driven to {limits[i, end]:.3f}"


@pytest.mark.parametrize("asset_id", ARTICULATED)
def test_handles_are_reachable_from_the_robot_base(asset_id):
    """With the asset at x = 0.45 m, the palm can be put 6 cm in front of each handle, facing it (IK)."""
    from gendex.solve.ik import ArmIK

    record = catalog()[asset_id]
    env = _make([{"name": "item", "asset": asset_id, "pos_m": [REACH_TEST_X, 0.0, 0.0], "fixed": True}])
    try:
        ik = ArmIK(env.agent)
        q0 = env.agent.robot.get_qpos()[0].numpy().astype(np.float64)
        for joint in record.joints:
            handle = env.handle_pos("item", joint.name)[0].numpy().astype(np.float64)
            found = None
            for roll in (0.0, math.pi / 2, -math.pi / 2):  # fingers up, then sideways
                # palm axes in the world: normal (-y) along +x (towards the object), fingers (+z) up, rolled about x
                c, s = math.cos(roll), math.sin(roll)
                pose_w = np.eye(4)
                pose_w[:3, :3] = np.array([[1, 0, 0], [0, c, -s], [0, s, c]]) @ PALM_FACING_X
                pose_w[:3, 3] = handle - np.array([0.06, 0.0, 0.0])
                found = ik.solve(sapien.Pose(pose_w), q0, restarts=6)
                if found is not None:
                    break
            assert found is not None, f"{asset_id}: no IK solution to the handle of {joint.name} at {handle.round(3)}"
    finally:
        env.close()


def test_shipped_files_carry_their_licence():
    from gendex_envs.assets.manifest import shipped_manifests

    for manifest in shipped_manifests():
        assert (manifest.parent / "LICENSE").is_file(), f"no LICENSE next to {manifest}"
    for record in catalog().values():
        assert record.entry.licence and record.entry.source, record.id


@pytest.mark.parametrize("asset_id", ARTICULATED)
def test_articulated_size_matches_catalog(articulated_scene, asset_id):
    env = articulated_scene
    art = env.articulations[f"j_{asset_id}"]
    # at the reset state (joints closed) the bounds are the catalog's
    art.set_qpos(env._art_init_qpos[f"j_{asset_id}"][None])
    lo, hi = entity_aabb(art)
    np.testing.assert_allclose(hi - lo, catalog()[asset_id].size_m, rtol=0.10, atol=0.005, err_msg=asset_id)


FREE_ARTICULATED = sorted(r.id for r in catalog().values() if r.articulated and not r.entry.fixed_base)


def test_free_articulated_assets_rest_on_table():
    assert FREE_ARTICULATED, "laptops and boxes with lids stand free"
    objs = [{"name": f"f_{aid}", "asset": aid, "pos_m": [x, y, 0.0]}
            for aid, (x, y) in zip(FREE_ARTICULATED, _grid_positions(len(FREE_ARTICULATED), 0.6), strict=True)]
    env = _make(objs, 0.6)
    try:
        start = {o["name"]: env.obj(o["name"]).pose.p[0].clone() for o in objs}
        _idle(env, 2.0)
        for o in objs:
            p = env.obj(o["name"]).pose.p[0]
            assert torch.isfinite(p).all() and torch.linalg.norm(p - start[o["name"]]).item() < 0.01, o["asset"]
    finally:
        env.close()
