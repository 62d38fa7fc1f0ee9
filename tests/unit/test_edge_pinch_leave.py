"""How the index leaves a dragged ring (``EdgePinch._leave_ring``): up where the arm reaches, curled where it does not.

The arm's IK is replaced by a reach limit in height; the ring, the fingertip and the emitted targets are plain arrays.
"""

from __future__ import annotations

import numpy as np
import pytest

from gendex.solve.edge_drag import CURL_INDEX
from gendex.solve.edge_pinch import EdgePinch

JOINTS = ["arm0", "FFJ2", "FFJ1", "FFJ0"]
RING = np.array([-0.2, 0.62, 0.003])


class _Motion:
    """Drive targets of one arm joint and the index's flexion joints."""

    def __init__(self):
        self.q = np.zeros(len(JOINTS))

    def target(self) -> np.ndarray:
        return self.q.copy()

    def with_hand(self, q: np.ndarray, hand: dict[str, float]) -> np.ndarray:
        q = q.copy()
        for j, v in hand.items():
            q[JOINTS.index(j)] = v
        return q

    def ramp(self, goal: np.ndarray, steps: int):
        start = self.q.copy()
        for k in range(1, steps + 1):
            self.q = start + (goal - start) * k / steps
            yield self.q.copy()


def _leave(monkeypatch, reach_z: float) -> tuple[list[np.ndarray], _Motion]:
    edge = EdgePinch.__new__(EdgePinch)
    edge.m, edge.name = _Motion(), "scissors"
    tips = {"now": np.array([RING[0] + 0.01, RING[1], 0.004])}  # the tip trails the ring's centre by 1 cm

    def palm_for_tip(self, rot, tip, q, restarts=0):
        return None if tip[2] > reach_z else np.asarray(tip)

    def move_tip(self, rot, tip, q=None):
        tips["now"] = np.asarray(tip, float)
        return tips["now"].copy()

    monkeypatch.setattr(EdgePinch, "ring", lambda self: RING.copy())
    monkeypatch.setattr(EdgePinch, "_tip", lambda self, q: tips["now"].copy())
    monkeypatch.setattr(EdgePinch, "_palm_for_tip", palm_for_tip)
    monkeypatch.setattr(EdgePinch, "_move_tip", move_tip)
    return list(edge._leave_ring(np.eye(3), tips["now"].copy())), edge.m


def test_the_index_rises_5_cm_out_of_the_centred_ring_where_the_arm_reaches(monkeypatch):
    out, motion = _leave(monkeypatch, reach_z=1.0)
    assert len(out) == 13  # 3 steps to the ring's centre, 10 up
    np.testing.assert_allclose(out[2], [RING[0], RING[1], 0.004], atol=1e-9)
    np.testing.assert_allclose(out[-1], [RING[0], RING[1], 0.054], atol=1e-9)
    assert not motion.q[1:].any()  # the index stayed straight


def test_the_index_curls_out_of_the_ring_where_the_arm_rises_no_higher(monkeypatch):
    """At the +y edge the arm often reaches no pose 2.5 cm above the dragged ring; the drag then ended with no IK
    (on the grasp benchmark's seeds 10100-10119, 3 of the scissors' 20 attempts and 3 of the wrench's)."""
    out, motion = _leave(monkeypatch, reach_z=0.02)
    rises = [t for t in out[3:] if t.shape == (3,)]
    assert [round(float(t[2]), 3) for t in rises] == [0.009, 0.014, 0.019]
    assert len(out) == 3 + 3 + 10  # then a 10-step ramp of the hand
    np.testing.assert_allclose(motion.q[1:], [CURL_INDEX[j] for j in JOINTS[1:]])


@pytest.mark.parametrize("reach_z", [0.0, 0.003])
def test_the_finger_leaves_from_where_it_is_when_it_cannot_be_centred(monkeypatch, reach_z):
    """No IK at the drag's height either (the centring steps): no centring; the curl still frees the finger."""
    out, motion = _leave(monkeypatch, reach_z=reach_z)
    assert len(out) == 10
    np.testing.assert_allclose(motion.q[1:], [CURL_INDEX[j] for j in JOINTS[1:]])
