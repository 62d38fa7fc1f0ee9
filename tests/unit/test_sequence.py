"""Ordered success ("A, then B, then C"): the spec's ``success.sequence`` and the tracker that latches its steps."""

from __future__ import annotations

import copy

import pytest
import torch

from gendex_envs.errors import TaskSpecError
from gendex_envs.spec import (
    ConditionSpec,
    SequenceStepSpec,
    SuccessSpec,
    dump_task_spec,
    load_task_spec,
    parse_task_spec,
)
from gendex_envs.success import SuccessTracker, conditions_hold


class _Env:
    """A drawer whose opening (0 closed, 1 open) the test sets, one row per env."""

    def __init__(self, n: int):
        self.num_envs, self.device = n, torch.device("cpu")
        self.opening = torch.zeros(n)

    def joint_open_fraction(self, name: str, joint: str | None = None) -> torch.Tensor:
        return self.opening


def at(fraction: float) -> ConditionSpec:
    return ConditionSpec(type="joint_at", object="drawer", fraction=fraction, max_error=0.1)


OPEN_THEN_CLOSE = SuccessSpec(description="the drawer was opened, then closed again", conditions=(at(0.0),),
                              sequence=(SequenceStepSpec(description="the drawer is open", conditions=(at(1.0),)),))


def run(success: SuccessSpec, openings: list[list[float]]) -> list[list[bool]]:
    """Success after each control step, per env, with the drawer at ``openings[t][env]``."""
    env = _Env(len(openings[0]))
    tracker = SuccessTracker(success, env.num_envs, env.device)
    out = []
    for t, row in enumerate(openings):
        env.opening = torch.tensor(row)
        holds = conditions_hold(env, success.conditions)
        step = torch.full((env.num_envs,), t)
        first = tracker.update(env, holds, step)
        again = tracker.update(env, holds, step)  # evaluate() called twice in one control step counts once
        assert first.tolist() == again.tolist()
        out.append(first.tolist())
    return out


def test_the_final_conditions_count_only_after_the_sequence():
    """Closed at the start is not "opened, then closed"; once opened, closing it succeeds, and the step stays done
    while the drawer swings back."""
    got = run(OPEN_THEN_CLOSE, [[0.0], [0.5], [1.0], [1.0], [0.5], [0.0], [0.0]])
    assert [g[0] for g in got] == [False, False, False, False, False, True, True]


def test_each_env_keeps_its_own_progress_and_a_reset_clears_it():
    got = run(OPEN_THEN_CLOSE, [[0.0, 1.0], [0.0, 0.0], [1.0, 0.0], [0.0, 0.0]])
    assert got == [[False, False], [False, True], [False, True], [True, True]]
    env = _Env(2)
    tracker = SuccessTracker(OPEN_THEN_CLOSE, 2, "cpu")
    env.opening = torch.tensor([1.0, 1.0])
    tracker.update(env, torch.tensor([False, False]), torch.tensor([0, 0]))
    tracker.reset(torch.tensor([0]))
    assert tracker.progress.tolist() == [0, 1]


def test_steps_go_in_order_one_control_step_apart_and_hold_their_hold_steps():
    """Three steps (half open, open, half open again) then closed: a step that held before its turn does not count,
    and a step with hold_steps 2 needs two consecutive control steps."""
    steps = (SequenceStepSpec(description="half", conditions=(at(0.5),)),
             SequenceStepSpec(description="open", conditions=(at(1.0),), hold_steps=2),
             SequenceStepSpec(description="half again", conditions=(at(0.5),)))
    success = SuccessSpec(description="half, open, half, closed", conditions=(at(0.0),), sequence=steps)
    openings = [1.0, 0.5, 1.0, 0.5, 1.0, 1.0, 0.5, 0.0]
    got = [g[0] for g in run(success, [[o] for o in openings])]
    # 1.0 first: not yet the open step's turn; 0.5 done; 1.0 once (streak broken by 0.5); 1.0 twice done; 0.5 done;
    # closed: success
    assert got == [False] * 7 + [True]


def test_task_hold_steps_count_after_the_sequence():
    success = SuccessSpec(description="opened, then closed for 3 steps", conditions=(at(0.0),), hold_steps=3,
                          sequence=OPEN_THEN_CLOSE.sequence)
    got = [g[0] for g in run(success, [[1.0], [0.0], [0.0], [0.0], [0.5], [0.0]])]
    assert got == [False, False, False, True, False, False]


def test_no_sequence_and_no_hold_is_the_judges_verdict():
    success = SuccessSpec(description="closed", conditions=(at(0.0),))
    assert [g[0] for g in run(success, [[0.0], [1.0], [0.0]])] == [True, False, True]


# ------------------------------------------------------------------------------ the spec
RAW = {"name": "OpenThenCloseDrawer", "instruction": "open the drawer, then close it",
       "objects": [{"name": "drawer", "asset": "ycb_013_apple", "pos_m": [0.3, 0.0, 0.0]}],
       "stages": [{"name": "reach", "instruction": "reach", "skill": "reach", "method": "motion_planning",
                   "control_joint": "arm", "target": "drawer"}],
       "success": {"description": "opened, then closed",
                   "conditions": [{"type": "joint_at", "object": "drawer", "fraction": 0.0}],
                   "sequence": [{"description": "open", "conditions": [{"type": "joint_open", "object": "drawer",
                                                                        "min_fraction": 0.9}]}]}}


def test_the_spec_takes_a_sequence_and_leaves_it_out_when_unset():
    spec = parse_task_spec(RAW)
    assert spec.success.sequence[0].conditions[0].type == "joint_open"
    plain = copy.deepcopy(RAW)
    del plain["success"]["sequence"]
    assert parse_task_spec(plain).success.sequence is None


@pytest.mark.parametrize("change, pattern", [
    (lambda s: s.update(sequence=[]), r"success.sequence = \[\] is not allowed; leave it out"),
    (lambda s: s["sequence"][0].update(conditions=[]), r"success.sequence\[0\].conditions = \[\] is not allowed"),
    (lambda s: s["sequence"][0].update(description=" "), r"success.sequence\[0\].description"),
    (lambda s: s["sequence"][0].update(hold_steps=-1), r"success.sequence\[0\].hold_steps = -1"),
    (lambda s: s["sequence"][0]["conditions"][0].update(object="cupboard"),
     r"success.sequence\[0\].conditions\[0\].object"),
    (lambda s: s["sequence"][0]["conditions"][0].update(fraction=0.5),
     r"success.sequence\[0\].conditions\[0\].fraction = 0.5 does not apply to type 'joint_open'"),
])
def test_the_spec_refuses_a_bad_sequence(change, pattern):
    raw = copy.deepcopy(RAW)
    change(raw["success"])
    with pytest.raises(TaskSpecError, match=pattern):
        parse_task_spec(raw)


def test_a_sequence_round_trips_through_yaml(tmp_path):
    spec = parse_task_spec(RAW)
    (tmp_path / "task.yaml").write_text(dump_task_spec(spec))
    assert load_task_spec(tmp_path / "task.yaml") == spec
