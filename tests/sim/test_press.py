"""Press primitives (gendex.solve.press): pushing a door shut, a lid open or shut and a lever round with the open
hand, on the reference tasks of those skills."""

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch

import gendex_envs  # noqa: F401
from gendex.solve import press
from gendex.solve.articulated import handle_local, read_joint
from gendex.solve.executor import StageExecutor
from gendex.solve.shape import ObjectShape

KWARGS = {"control_mode": "pd_joint_pos", "control_joint": "both"}


@pytest.fixture
def make_env(task_version):
    made = []

    def make(task: str):
        env = gym.make(task_version(task).env_id, **KWARGS)
        made.append(env)
        return env

    yield make
    for env in made:
        env.close()


def _run(env, seed, executor):
    obs, _ = env.reset(seed=seed)
    executor.reset(env, obs)
    info = {}
    while (action := executor.act(env, obs)) is not None:
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            break
    return info


@pytest.mark.parametrize(("task", "name"), [("TurnFaucet", "faucet"), ("CloseCabinet", "cabinet"),
                                            ("OpenTrashCan", "trash_can")])
def test_press_direction_is_where_the_grip_point_moves_in_the_simulator(make_env, task, name):
    env = make_env(task)
    u = env.unwrapped
    env.reset(seed=4)
    joint = read_joint(u, name)
    local = handle_local(u, name)
    before = u.handle_pos(name)[0].numpy().astype(np.float64)
    art = u.articulations[name]
    art.set_qpos(torch.tensor([[joint.q + 0.02]], dtype=torch.float32))
    moved = u.handle_pos(name)[0].numpy().astype(np.float64) - before
    predicted = joint.link[:3, :3] @ press.press_direction(joint, local)
    assert np.dot(moved / np.linalg.norm(moved), predicted) == pytest.approx(1.0, abs=2e-3)


def test_press_poses_touch_the_part_square_on_and_follow_it(make_env):
    """Every press pose puts its palm-frame contact point CONTACT_GAP_M off the door's surface on the side the push
    comes from, the palm facing the push (a shelf: the top of its bent fingers); along the door's path the contact
    point stays on the door (a pose that follows half the turn keeps the point, not the orientation)."""
    env = make_env("CloseCabinet")
    u = env.unwrapped
    env.reset(seed=2)
    joint = read_joint(u, "cabinet")
    shape = ObjectShape.of_actor(u.handle_link("cabinet"))
    poses = press.press_poses(joint, shape, handle_local(u, "cabinet"), -1.0)
    assert {p.site for p in poses} == {"palm", "fingers", "shelf"}
    assert {p.follow for p in poses if p.site != "shelf"} == {1.0, 0.5}
    assert {p.follow for p in poses if p.site == "shelf"} == set(press.SHELF_FOLLOWS)
    assert [p.site for p in poses].index("shelf") > max(i for i, p in enumerate(poses) if p.site != "shelf")
    for pose in poses:
        palm = pose.palm_at(joint, joint.q).to_transformation_matrix()
        touch = palm[:3, :3] @ pose.contact + palm[:3, 3]
        # the palm's skin faces -y of the palm frame; a shelf's bent fingers face -z (the palm's knuckle end)
        push = palm[:3, :3] @ (np.array([0.0, 0.0, -1.0]) if pose.site == "shelf" else np.array([0.0, -1.0, 0.0]))
        depth = shape.posed(joint.link).ray_intervals(touch, push)[0][0]
        assert depth == pytest.approx(press.CONTACT_GAP_M, abs=1e-4), pose
        surface = np.linalg.inv(joint.link) @ np.append(touch + depth * push, 1.0)
        m = joint.link[:3, :3] @ (-press.press_direction(joint, surface[:3]))
        assert np.dot(push, m) == pytest.approx(1.0, abs=1e-6)  # square on to the path where it touches
        local = np.linalg.inv(joint.link) @ np.append(touch, 1.0)
        later = pose.palm_at(joint, joint.q - 0.3).to_transformation_matrix()
        assert np.allclose(later[:3, :3] @ pose.contact + later[:3, 3], joint.point_at(local[:3], joint.q - 0.3),
                           atol=1e-5)
        turned = np.degrees(np.arccos(np.clip((np.trace(palm[:3, :3].T @ later[:3, :3]) - 1) / 2, -1, 1)))
        assert turned == pytest.approx(np.degrees(0.3) * abs(pose.follow), abs=0.01)


def test_the_press_stops_where_gravity_takes_over_only_for_a_lid(make_env):
    """A lid pushed back over upright is let go where gravity closes it hard enough; a door on a vertical hinge
    gets no help from gravity and is pushed all the way."""
    env = make_env("CloseTrashCan")
    env.reset(seed=0)
    executor = StageExecutor()
    executor.reset(env, None)
    presses = executor._presses
    u = env.unwrapped
    joint = read_joint(u, "trash_can")
    goal = presses._press_goal(u.task_spec.stages[-1], -1.0)
    stop = presses._handover("trash_can", joint, -1.0, goal)
    assert goal < stop < np.pi / 2 < joint.q
    env = make_env("CloseCabinet")
    env.reset(seed=0)
    executor.reset(env, None)
    joint = read_joint(env.unwrapped, "cabinet")
    goal = executor._presses._press_goal(env.unwrapped.task_spec.stages[-1], -1.0)
    assert executor._presses._handover("cabinet", joint, -1.0, goal) == goal


@pytest.mark.parametrize(("task", "name", "done"), [
    ("CloseCabinet", "cabinet", lambda f: f < 0.1),
    ("TurnFaucet", "faucet", lambda f: f >= 0.8),
    pytest.param(*("CloseTrashCan", "trash_can", lambda f: f < 0.1), marks=pytest.mark.slow),
    pytest.param(*("OpenTrashCan", "trash_can", lambda f: f >= 0.5), marks=pytest.mark.slow),
    ("OpenBoxLid", "box", lambda f: f >= 0.5),
    pytest.param(*("CloseMicrowave", "microwave", lambda f: f < 0.1), marks=pytest.mark.slow),
    pytest.param(*("CloseOvenCompact", "oven", lambda f: f < 0.1), marks=pytest.mark.slow),
])
def test_the_executor_presses_parts_no_stage_grasps(make_env, task, name, done):
    env = make_env(task)
    u = env.unwrapped
    for seed in (905, 906):
        executor = StageExecutor()
        info = _run(env, seed, executor)
        fraction = float(u.joint_open_fraction(name)[0])
        assert bool(info["success"]) and done(fraction), (task, seed, fraction)
        assert [log.primitive for log in executor.logs][:2] == ["approach_press", "press"]


def test_an_oven_door_lying_open_on_its_stop_is_lifted_shut_by_a_shelf_under_its_edge(make_env):
    """The open oven door lies level on its stop with its handle underneath, 5 cm over the table: no palm or
    fingertip press fits under it, and the shelf lift (fingers bent square under the free edge beyond the handle,
    the palm turning against the door as it rises) is what the executor chooses and what shuts it."""
    env = make_env("CloseOvenCompact")
    executor = StageExecutor()
    info = _run(env, 907, executor)
    assert executor._presses.grasp.site == "shelf"
    assert bool(info["success"]) and float(env.unwrapped.joint_open_fraction("oven")[0]) < 0.1


def test_a_lid_opened_for_later_stages_is_pushed_past_its_balance_and_stays_open():
    """A composed task opens a tall bin's lid, then sets a banana on a plate (generated by the offline backend,
    batch seed 41953). Pressed only to the task's open fraction, the lid falls shut behind the hand once it leaves
    for the banana; the press now goes on past the point where gravity stops pulling it back."""
    import yaml

    from gendex.solve.attempt import run_attempt
    from gendex_envs.spec import parse_task_spec
    from gendex_envs.task_env import TaskEnv

    path = Path(__file__).parents[1] / "data" / "tasks" / "OpenTrashCanTallThenSetBananaOnPlate.yaml"
    spec = parse_task_spec(yaml.safe_load(path.read_text()), source=str(path))
    env = TaskEnv(task_spec=spec, **KWARGS, obs_mode="none", render_backend="none")
    try:
        env.reset(seed=600)
        executor = StageExecutor()
        executor.reset(env, None)
        presses, opening = executor._presses, spec.stages[1]
        stay, plain = presses._press_goal(opening, 1.0), presses._press_goal(opening, 1.0, stay=False)
        gravity = presses._gravity("trash_can", read_joint(env, "trash_can"), np.array([plain, stay]), 1.0)
        assert plain < stay and gravity[0] < 0 <= gravity[1]  # falls back from the plain goal, not from the other
        out = run_attempt(env, executor, 600)
        assert out.succeeded, out.failure
        assert float(env.joint_open_fraction("trash_can")[0]) >= 0.5
        assert [log.stage for log in executor.logs][-1] == "release_banana"  # the lid stayed open all along
    finally:
        env.close()


@pytest.mark.parametrize("seed", [779401, pytest.param(779403, marks=pytest.mark.slow)])
def test_the_arm_pressing_a_door_shut_leaves_a_standing_bottle_standing(seed):
    """A fresh batch's task shuts a microwave, then sets a 22 cm bottle, standing between the robot and the
    microwave, on a board. The press was planned clear of the microwave alone, and on these seeds the forearm,
    following the door's arc, knocked the bottle over; then no grasp of the lying bottle held. The press is now
    planned clear of the other objects too: the bottle stands until the hand takes it, and the task is done."""
    import yaml

    from gendex.episode_loop import Hooks
    from gendex.solve.attempt import run_attempt
    from gendex_envs.spec import parse_task_spec
    from gendex_envs.task_env import TaskEnv

    path = Path(__file__).parents[1] / "data" / "tasks" / "CloseMicrowaveStandardThenSetBottleOnCuttingBoard.yaml"
    spec = parse_task_spec(yaml.safe_load(path.read_text()), source=str(path))
    env = TaskEnv(task_spec=spec, **KWARGS, obs_mode="none", render_backend="none")
    try:
        executor = StageExecutor()
        lowest = []  # the bottle's up-axis z while the stages before its grasp run

        def watch(_obs):
            if executor.stage_index < 3:
                w, x, y, z = env.obj("bottle").pose.q[0].tolist()
                lowest.append(1 - 2 * (x * x + y * y))

        out = run_attempt(env, executor, seed, Hooks(on_reset=lambda obs, _info: watch(obs),
                                                     on_step=lambda step: watch(step.obs)))
        assert min(lowest) > 0.95, f"the bottle tipped to {min(lowest):.2f} before the hand reached it"
        assert [s.name for s in spec.stages][:3] == ["reach_microwave", "close_microwave", "reach_bottle"]
        assert out.succeeded, out.failure
    finally:
        env.close()


def _generated(name: str):
    """A task the offline author wrote for a request of the task language (``tests/data/tasks``), as an env."""
    import yaml

    from gendex_envs.spec import parse_task_spec
    from gendex_envs.task_env import TaskEnv

    path = Path(__file__).parents[1] / "data" / "tasks" / f"{name}.yaml"
    spec = parse_task_spec(yaml.safe_load(path.read_text()), source=str(path))
    return TaskEnv(task_spec=spec, **KWARGS, obs_mode="none", render_backend="none")


@pytest.mark.parametrize("seed", [7000, pytest.param(7004, marks=pytest.mark.slow)])
def test_a_lever_turned_off_is_pushed_back_shut_by_a_shelf_of_fingers(seed):
    """'Close the valve' (offline author, seed 11): the lever starts open and must end below 10 % of its range.
    Fingertip presses slid off it at 0.15-0.17 rad (goal 0.10) on every dev seed that chose one; the executor now
    tries the shelf first for a lever turned back, and it carries the lever home."""
    from gendex.solve.attempt import run_attempt

    env = _generated("TurnValveLeverOff")
    try:
        executor = StageExecutor()
        out = run_attempt(env, executor, seed)
        assert out.succeeded, out.failure
        assert executor._presses.grasp.site == "shelf"
        assert float(env.joint_open_fraction("valve")[0]) < 0.1
    finally:
        env.close()


@pytest.mark.parametrize(("name", "obj", "fraction"), [("OpenDrawerChest1Half", "drawer_chest", 0.5),
                                                       ("TurnValveLever45Degrees", "valve", 0.654)])
def test_a_joint_set_part_way_stops_there_and_stays(name, obj, fraction):
    """'Open the drawer halfway' (a hooked pull) and 'turn the valve 45 degrees' (a press): the move stops at the
    joint_at fraction instead of running past it, and the success (within 0.1, held 10 steps) is met."""
    from gendex.solve.attempt import run_attempt

    env = _generated(name)
    try:
        out = run_attempt(env, StageExecutor(), 7001)
        assert out.succeeded, out.failure
        assert abs(float(env.joint_open_fraction(obj)[0]) - fraction) <= 0.1
    finally:
        env.close()
