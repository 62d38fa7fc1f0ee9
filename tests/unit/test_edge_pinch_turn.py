"""The turn that points a flat tool's ring at the table's side edge before it is dragged there
(``edge_geometry.turn_to_edge``): a finger wedged in the ring turns the tool with the hand."""

from __future__ import annotations

import numpy as np
import pytest

from gendex.solve.edge_geometry import TURN_MAX_RAD, TURN_MIN_RAD, turn_to_edge


def _heading_after(ring, com, turn):
    d = np.asarray(ring[:2], float) - np.asarray(com[:2], float)
    a = np.arctan2(d[1], d[0]) + turn
    return np.array([np.cos(a), np.sin(a)])


@pytest.mark.parametrize("angle_deg", [-80.0, -45.0, -20.0, 20.0, 60.0, 85.0])
@pytest.mark.parametrize("side", [1.0, -1.0])
def test_the_turn_points_the_ring_at_the_edge(angle_deg, side):
    """A ring ``angle_deg`` off the edge's normal (from the centre of mass) is turned onto it."""
    a = np.arctan2(side, 0.0) + np.radians(angle_deg)
    com = np.array([0.1, -0.05, 0.0])
    ring = com + 0.08 * np.array([np.cos(a), np.sin(a), 0.0])
    turn = turn_to_edge(ring, com, side)
    assert turn == pytest.approx(-np.radians(angle_deg), abs=1e-9)
    assert _heading_after(ring, com, turn) == pytest.approx([0.0, side], abs=1e-9)


def test_a_ring_facing_the_edge_is_not_turned():
    com = np.zeros(3)
    assert turn_to_edge(np.array([0.0, 0.08, 0.0]), com, 1.0) == 0.0
    small = 0.9 * TURN_MIN_RAD
    assert turn_to_edge(np.array([0.08 * np.sin(small), -0.08 * np.cos(small), 0.0]), com, -1.0) == 0.0


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_a_ring_facing_away_is_turned_at_most_the_limit(side):
    """A ring pointing away from the edge would need half a turn; the hand turns at most ``TURN_MAX_RAD``, towards
    the edge (the drag then pulls the ring, and the tool trails it less slanted)."""
    com = np.zeros(3)
    ring = np.array([0.01, -side * 0.08, 0.0])  # away from the edge, a little towards +x
    turn = turn_to_edge(ring, com, side)
    assert abs(turn) == pytest.approx(TURN_MAX_RAD)
    before = abs(np.arctan2(ring[0], side * ring[1]))
    h = _heading_after(ring, com, turn)
    assert abs(np.arctan2(h[0], side * h[1])) < before
