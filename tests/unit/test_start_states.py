"""StartStates files and stage lookup: round trip, atomic writes, and named errors for bad input."""

import numpy as np
import pytest

from gendex_envs.errors import StageError
from gendex_envs.spec import resolve_stage
from gendex_envs.start_states import StartStates
from gendex_envs.task_version import TaskLayout


def _states(m=3, d=7):
    rng = np.random.default_rng(0)
    return StartStates(stage="grasp_bottle", source="executor", state=rng.normal(size=(m, d)).astype(np.float32),
                       obj_reset_pos={"bottle": rng.normal(size=(m, 3)).astype(np.float32)},
                       obj_reset_quat={"bottle": _unit(rng.normal(size=(m, 4))).astype(np.float32)})


def _unit(q):
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def test_round_trip_and_no_leftovers(tmp_path):
    s = _states()
    path = s.save(TaskLayout(tmp_path).start_states("grasp_bottle"))
    back = StartStates.load(path)
    assert back.stage == "grasp_bottle" and back.source == "executor" and len(back) == 3
    np.testing.assert_array_equal(back.state, s.state)
    np.testing.assert_array_equal(back.obj_reset_pos["bottle"], s.obj_reset_pos["bottle"])
    np.testing.assert_array_equal(back.obj_reset_quat["bottle"], s.obj_reset_quat["bottle"])
    assert sorted(p.name for p in path.parent.iterdir()) == ["grasp_bottle.npz"]  # temp file renamed away


def test_concat_joins_rows():
    joined = StartStates.concat([_states(2), _states(3)])
    assert len(joined) == 5 and joined.obj_reset_pos["bottle"].shape == (5, 3)


@pytest.mark.parametrize("bad", [
    dict(state=np.zeros((0, 4))),
    dict(state=np.zeros(4)),
    dict(state=np.zeros((2, 4)), obj_reset_pos={"bottle": np.zeros((3, 3))}),
])
def test_bad_shapes_are_named(bad):
    with pytest.raises(StageError, match="start states of stage"):
        StartStates(stage="s", **bad)


def test_load_rejects_foreign_files(tmp_path):
    path = tmp_path / "x.npz"
    np.savez(path, something=np.zeros(3))
    with pytest.raises(StageError, match="not a GenDex start-state file"):
        StartStates.load(path)
    with pytest.raises(StageError, match="no start states"):
        StartStates.load(tmp_path / "missing.npz")


def test_resolve_stage_by_name_index_and_errors(task_version):
    spec = task_version("PickUpBottle", 0).spec
    assert resolve_stage(spec, 1)[1].name == "grasp_bottle"
    assert resolve_stage(spec, "2")[1].name == "lift_bottle"
    assert resolve_stage(spec, "approach_bottle")[0] == 0
    with pytest.raises(StageError, match="Did you mean: 'grasp_bottle'"):
        resolve_stage(spec, "grasp_botle")
    with pytest.raises(StageError, match=r"stages 0\.\.2"):
        resolve_stage(spec, 3)


def test_stage_reward_falls_back_to_task_reward(task_copy):
    version = task_copy("PickUpBottle", as_name="ScratchBottle")
    layout: TaskLayout = version.files
    layout.stage_reward("lift_bottle").unlink()
    assert version.reward_path("grasp_bottle") == layout.stage_reward("grasp_bottle")
    assert version.reward_path("lift_bottle") == layout.reward
    assert version.reward("lift_bottle").path == layout.reward.resolve()
