"""How the index goes through a dragged ring before it curls (``EdgePinch._through_ring``): straight down to
``HOOK_TIP_Z_M``; back up and once more where the ring goes down with it; no hook where it jams twice or the arm does
not follow.

The arm's IK is replaced by the tip going where it is sent (down to a floor, where the arm is stopped); the ring's
height follows the fingertip while the finger is jammed in it.
"""

from __future__ import annotations

import numpy as np
import pytest

from gendex.solve.edge_drag import HOOK_JAM_M, HOOK_TIP_Z_M
from gendex.solve.edge_pinch import EdgePinch

RING = np.array([-0.2, 0.62, 0.0035])
START_Z = 0.004


class _Motion:
    def target(self) -> np.ndarray:
        return np.zeros(1)

    def qpos(self) -> np.ndarray:
        return np.zeros(1)


def _run(gen):
    out = []
    while True:
        try:
            out.append(next(gen))
        except StopIteration as stop:
            return out, stop.value


def _through(monkeypatch, jams: int = 0, floor: float = -1.0) -> tuple[list[np.ndarray], bool]:
    """The emitted tips and the outcome, for a finger that jams in the ring on its first ``jams`` descents, the arm
    taking the tip no lower than ``floor``."""
    edge = EdgePinch.__new__(EdgePinch)
    edge.m, edge.name = _Motion(), "scissors"
    state = {"tip": np.array([RING[0], RING[1], START_Z]), "ring_z": RING[2], "descents": 0, "low": False}

    def move_tip(self, rot, tip, q=None):
        state["tip"] = np.array([tip[0], tip[1], max(float(tip[2]), floor)])
        z = state["tip"][2]
        if z < 0.0:
            state["low"] = True
        elif state["low"]:  # back up: one descent done, the ring back on the table
            state["low"], state["descents"], state["ring_z"] = False, state["descents"] + 1, RING[2]
        if state["descents"] < jams:
            state["ring_z"] = min(RING[2], z)  # the ring goes down with the finger
        return state["tip"].copy()

    monkeypatch.setattr(EdgePinch, "ring", lambda self: np.array([RING[0], RING[1], state["ring_z"]]))
    monkeypatch.setattr(EdgePinch, "_tip", lambda self, q: state["tip"].copy())
    monkeypatch.setattr(EdgePinch, "_palm_for_tip", lambda self, rot, tip, q, restarts=0: np.asarray(tip))
    monkeypatch.setattr(EdgePinch, "_move_tip", move_tip)
    return _run(edge._through_ring([np.eye(3)] * 8))


def test_a_finger_that_passes_goes_straight_through_the_ring(monkeypatch):
    tips, through = _through(monkeypatch)
    assert through
    z = [t[2] for t in tips]
    assert z[:7] == [START_Z] * 7  # straightened where it is
    assert z[-1] == pytest.approx(HOOK_TIP_Z_M)
    assert np.all(np.diff(z) <= 0)  # never back up


def test_a_jammed_finger_goes_back_up_and_passes_on_its_second_try(monkeypatch):
    tips, through = _through(monkeypatch, jams=1)
    assert through
    z = np.array([t[2] for t in tips])
    low = int(np.argmax(z < 0.0))  # in the ring
    assert z[low:].max() == pytest.approx(START_Z)  # back at the ring's height once
    assert z[low:].min() == pytest.approx(HOOK_TIP_Z_M)
    assert z[-1] == pytest.approx(HOOK_TIP_Z_M)


def test_no_hook_when_the_finger_jams_twice(monkeypatch):
    tips, through = _through(monkeypatch, jams=2)
    assert not through
    assert tips[-1][2] == pytest.approx(START_Z)  # left at the ring's height, for the pinch
    assert min(t[2] for t in tips) > -2 * HOOK_JAM_M  # stopped early each time, before the tool tips over


def test_no_hook_when_the_arm_does_not_follow_the_finger_down(monkeypatch):
    tips, through = _through(monkeypatch, floor=0.0)
    assert not through
    assert min(t[2] for t in tips) == 0.0
