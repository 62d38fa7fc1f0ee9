"""``RigidPrimitives.choose_grasp`` takes the first grasp that held cleanly in its physics trial. One whose closing
pushed the object across the table (``TrialResult.shoved``) held on the edge of holding: it is kept as a fallback,
taken only when no clean one holds, the least pushed first and before one that swung the object over.

The synthesizer, the IK and the trials are stand-ins: each candidate is reachable, and its trial's result is scripted.
"""

from __future__ import annotations

import types

import numpy as np
import pytest
import sapien

import gendex.solve.rigid as rigid
from gendex.solve.grasp import GraspPlan
from gendex.solve.grasp_trial import SHOVED_M, TrialResult
from gendex.solve.rigid import RigidConfig, RigidPrimitives
from gendex_envs.errors import ExecutionError


def _plan(i: int, kind: str | None = None) -> GraspPlan:
    return GraspPlan(kind or f"candidate-{i}", sapien.Pose([0.5, 0.0, 0.1]), np.array([0.0, 0.0, -1.0]))


def _held(plan: GraspPlan, pushed_m: float = 0.0, spread: float = 1.0) -> TrialResult:
    return TrialResult(plan, True, 0.1, True, 0.0, 40, spread=spread, pushed_m=pushed_m)


def _dropped(plan: GraspPlan) -> TrialResult:
    return TrialResult(plan, False, 0.0, False, 0.0, 40, why="rose 0.000 m")


class _Synth:
    def __init__(self, *args, plans=(), families=("top",)):
        self.plans, self._families = plans, families

    def families(self):
        return self._families

    def candidates(self):
        return iter(self.plans)


class _Trials:
    def __init__(self, outcomes):
        self.outcomes, self.tried = outcomes, []

    def trial(self, plan, q, name, require, shape):
        self.tried.append(plan)
        return self.outcomes[len(self.tried) - 1](plan)


def _choose(monkeypatch, outcomes, set_on=None, fits=None, families=("top",), config=None, kinds=None, ring=False):
    """``outcomes[i](plan)``: the trial result of candidate i (of kind ``kinds[i]``; default ``candidate-i``);
    ``ring``: the object is a ringed flat tool. Returns (chosen plan, plans tried)."""
    plans = tuple(_plan(i, kinds[i] if kinds else None) for i in range(len(outcomes)))
    monkeypatch.setattr(rigid, "GraspSynthesizer", lambda *a, **kw: _Synth(plans=plans, families=families))
    monkeypatch.setattr(rigid, "find_ring", lambda shape: object() if ring else None)
    monkeypatch.setattr(rigid, "object_heading", lambda *a: 0.0)
    monkeypatch.setattr(rigid, "px_bodies", lambda obj: [types.SimpleNamespace(mass=0.1)])
    monkeypatch.setattr(rigid, "fits_on", lambda shape, target: fits)
    prims = RigidPrimitives.__new__(RigidPrimitives)
    prims.config = config or RigidConfig(max_trials=len(outcomes))
    ik = types.SimpleNamespace(base=sapien.Pose(), solve=lambda pose, q, restarts=0, valid=None: np.zeros(3))
    prims.m = types.SimpleNamespace(ik=ik, collision=types.SimpleNamespace(is_free=None), target=lambda: np.zeros(3),
                                    with_hand=lambda q, hand: q, avoid_objects=lambda exclude: None)
    prims.env = types.SimpleNamespace(objects=("cube", "bowl"), articulations=(), table_height=0.0,
                                      obj=lambda name: None,
                                      asset_record=lambda name: types.SimpleNamespace(tags=("container",)))
    prims._hand, prims._trials, prims._synth, prims.trial_log = object(), _Trials(outcomes), None, []
    shape = types.SimpleNamespace(footprint=lambda: types.SimpleNamespace(center=np.zeros(2)))
    prims._shapes = {"cube": shape, "bowl": shape}
    prims.shape = lambda name: prims._shapes[name]
    try:
        plan, _ = prims.choose_grasp("cube", set_on=set_on)
    except ExecutionError as err:
        err.tried = prims._trials.tried
        raise
    return plan, prims._trials.tried


def test_a_clean_hold_after_a_shoved_one_is_taken(monkeypatch):
    plan, tried = _choose(monkeypatch, [lambda p: _held(p, pushed_m=0.04), lambda p: _held(p, pushed_m=0.005),
                                        lambda p: _held(p)])
    assert plan.kind == "candidate-1" and len(tried) == 2


def test_when_every_hold_was_shoved_the_least_pushed_is_the_fallback(monkeypatch):
    plan, tried = _choose(monkeypatch, [lambda p: _held(p, pushed_m=0.06), _dropped,
                                        lambda p: _held(p, pushed_m=SHOVED_M + 0.005), _dropped])
    assert plan.kind == "candidate-2" and len(tried) == 4


def test_a_shoved_hold_that_fits_comes_before_one_that_swung_over(monkeypatch):
    fits = lambda spread: spread < 1.5  # noqa: E731  (the bowl takes a footprint grown up to 1.5x)
    plan, _ = _choose(monkeypatch, [lambda p: _held(p, spread=1.8), lambda p: _held(p, pushed_m=0.05, spread=1.3)],
                      set_on="bowl", fits=fits)
    assert plan.kind == "candidate-1"
    plan, _ = _choose(monkeypatch, [lambda p: _held(p, spread=1.8), lambda p: _held(p, spread=1.6)],
                      set_on="bowl", fits=fits)
    assert plan.kind == "candidate-1"  # the least swung of those that do not fit


def test_no_hold_at_all_is_a_failed_grasp(monkeypatch):
    with pytest.raises(ExecutionError) as err:
        _choose(monkeypatch, [_dropped, _dropped])
    assert err.value.cause == "grasp_failed"


def test_a_shoved_trial_says_so():
    plan = _plan(0)
    assert "pushed 0.050 m while closing" in str(_held(plan, pushed_m=0.05))
    assert "pushed" not in str(_held(plan, pushed_m=0.01))
    assert _held(plan, pushed_m=SHOVED_M + 1e-4).shoved and not _held(plan, pushed_m=SHOVED_M).shoved


@pytest.mark.parametrize("families, budget", [(("top", "side"), 10), (("pinch",), 30), (("pinch", "tip"), 48)])
def test_a_ball_only_a_pinch_holds_gets_more_trials(monkeypatch, families, budget):
    """Budgets: 10 trials; 30 where a precision pinch is the only grasp (a golf ball's near misses push it while
    closing); 48 where fingertip pinches at the table join in."""
    config = RigidConfig(max_trials=10, pinch_trials=30, thin_trials=48)
    with pytest.raises(ExecutionError) as err:
        _choose(monkeypatch, [_dropped] * 60, families=families, config=config)
    assert err.value.cause == "grasp_failed" and len(err.value.tried) == budget


KINDS = ["top", "pinch"] * 30
"""Candidates alternating between a top grasp and a pinch, as the synthesizer ranks an object with both."""


def test_when_none_of_the_budget_held_the_pinches_go_on_up_to_pinch_trials(monkeypatch):
    """The cheese wedge (top and pinch grasps) ran out of its 10 trials on 3 of 20 fresh seeds; its pinches go on,
    to 30 trials in all, and the first that holds is taken."""
    config = RigidConfig(max_trials=10, pinch_trials=30, thin_trials=48)
    outcomes = [_dropped] * 60
    with pytest.raises(ExecutionError) as err:
        _choose(monkeypatch, outcomes, families=("top", "pinch"), config=config, kinds=KINDS)
    tried = err.value.tried
    assert len(tried) == 30 and [p.kind for p in tried[10:]] == ["pinch"] * 20  # only pinches after the first ten
    outcomes[16] = _held  # the 17th trial (the scripted outcomes go by trial) holds
    plan, tried = _choose(monkeypatch, outcomes, families=("top", "pinch"), config=config, kinds=KINDS)
    assert plan is tried[-1] and len(tried) == 17 and plan.kind == "pinch"


def test_an_attempt_that_held_within_the_budget_or_a_ringed_tool_gets_no_more_trials(monkeypatch):
    config = RigidConfig(max_trials=10, pinch_trials=30, thin_trials=48)
    shoved = [_dropped] * 9 + [lambda p: _held(p, pushed_m=SHOVED_M + 0.01)] + [_held] * 50
    plan, tried = _choose(monkeypatch, shoved, families=("top", "pinch"), config=config, kinds=KINDS)
    assert len(tried) == 10 and plan is tried[-1]  # the shoved hold of the tenth trial is the fallback, as before
    with pytest.raises(ExecutionError) as err:  # a flat tool with a ring is dragged to the edge instead
        _choose(monkeypatch, [_dropped] * 60, families=("top", "pinch"), config=config, kinds=KINDS, ring=True)
    assert len(err.value.tried) == 10
