"""The edge grasp is tried whole, variant by variant, before the robot does it (``gendex/solve/edge_trial.py``): the
first variant that held in a trial is the one done, the first variant where none held, and the trials go into the
executor's trial log. The physics trial itself is a stand-in here (``tests/sim/test_edge_trial.py`` runs real ones)."""

from __future__ import annotations

import pytest

import gendex.solve.edge_trial as edge_trial
from gendex.solve.edge_drag import DRAG_AIM_X_M, EdgeVariant
from gendex.solve.edge_trial import VARIANTS, EdgeTrials
from gendex.solve.grasp_trial import TrialResult
from gendex.solve.planner import ArmPlanner


class _Trials:
    """Holds in the trials numbered in ``holds`` (0-based); records which ran."""

    speed = None

    def __init__(self, holds: set[int]):
        self.holds, self.ran = holds, []

    def rehearse(self, main, name, run):
        k = len(self.ran)
        self.ran.append(run)
        held = k in self.holds
        return TrialResult(None, held, 0.15 if held else 0.0, held, 0.0, 100, "" if held else "rose 0.000 m")


class _Edge:
    def __init__(self, past: bool):
        self.past = past

    def past_edge(self) -> bool:
        return self.past


@pytest.fixture
def ring_past_edge(monkeypatch):
    """Where the tool's ring is: set ``ring_past_edge["past"]`` (the edge grasp's geometry is a stand-in)."""
    where = {"past": False}
    monkeypatch.setattr(edge_trial, "posed", lambda shape, m, name: None)
    monkeypatch.setattr(edge_trial.EdgePinch, "of", classmethod(lambda cls, m, hand, name, shape: _Edge(where["past"])))
    return where


@pytest.mark.parametrize("holds,chosen,tried", [({0}, 0, 1), ({1, 2}, 1, 2), ({3}, 3, 4),
                                                (set(), 0, len(VARIANTS))])
def test_the_first_variant_that_held_is_chosen(holds, chosen, tried, ring_past_edge):
    trials = _Trials(holds)
    log: list[TrialResult] = []
    variant = EdgeTrials(trials, hand=None, shape=None).choose(None, "obj", log)
    assert variant == VARIANTS[chosen]
    assert len(trials.ran) == tried and len(log) == tried
    assert [r.held for r in log] == [k in holds for k in range(tried)]


def test_a_ring_over_the_edge_already_is_tried_once(ring_past_edge):
    """A second edge grasp after a slip finds the ring past the edge: no drag, so the variants would be one trial
    repeated."""
    ring_past_edge["past"] = True
    trials = _Trials(set())
    assert EdgeTrials(trials, hand=None, shape=None).choose(None, "obj") == VARIANTS[0]
    assert len(trials.ran) == 1


def test_the_variants_cover_both_side_edges_two_places_along_them_and_no_turn():
    assert VARIANTS[0] == EdgeVariant()  # the drag as it was before the trials: its ring's own side edge first
    assert {v.other_side for v in VARIANTS} == {False, True} and {v.turn for v in VARIANTS} == {False, True}
    assert len({v.aim_x_m for v in VARIANTS}) >= 2 and DRAG_AIM_X_M in {v.aim_x_m for v in VARIANTS}
    assert len(set(VARIANTS)) == len(VARIANTS)


def test_a_planner_can_go_on_with_another_planners_searches():
    """A trial plans the paths the robot's planner would plan next: same seed, same rank of search."""
    a = ArmPlanner.__new__(ArmPlanner)
    a.reseed(17)
    a._searches = 5
    b = ArmPlanner.__new__(ArmPlanner)
    b.reseed(3)
    b.follow(a)
    assert (b.seed, b._searches) == (17, 5)
