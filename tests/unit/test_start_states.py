"""StartStates files and stage lookup: round trip, atomic writes, and named errors for bad input."""

import numpy as np
import pytest

from gendex_envs.errors import StageError
from gendex_envs.spec import load_task_spec
from gendex_envs.stage import StartStates, resolve_stage, stage_reward_path

BOTTLE = "generated_tasks/PickUpBottle/v0"


def _states(m=3, d=7):
    rng = np.random.default_rng(0)
    return StartStates(stage="grasp_bottle", source="executor", state=rng.normal(size=(m, d)).astype(np.float32),
                       obj_reset_pos={"bottle": rng.normal(size=(m, 3)).astype(np.float32)},
                       obj_reset_quat={"bottle": rng.normal(size=(m, 4)).astype(np.float32)})


def test_round_trip_and_no_leftovers(tmp_path):
    s = _states()
    path = s.save(tmp_path / "start_states" / "grasp_bottle.npz")
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


def test_resolve_stage_by_name_index_and_errors():
    spec = load_task_spec(f"{BOTTLE}/task.yaml")
    assert resolve_stage(spec, 1)[1].name == "grasp_bottle"
    assert resolve_stage(spec, "2")[1].name == "lift_bottle"
    assert resolve_stage(spec, "approach_bottle")[0] == 0
    with pytest.raises(StageError, match="Did you mean: 'grasp_bottle'"):
        resolve_stage(spec, "grasp_botle")
    with pytest.raises(StageError, match=r"stages 0\.\.2"):
        resolve_stage(spec, 3)


def test_stage_reward_falls_back_to_task_reward(tmp_path):
    (tmp_path / "stage_rewards").mkdir()
    (tmp_path / "stage_rewards" / "grasp.py").write_text("")
    assert stage_reward_path(tmp_path, "grasp").name == "grasp.py"
    assert stage_reward_path(tmp_path, "lift") == tmp_path / "reward.py"
