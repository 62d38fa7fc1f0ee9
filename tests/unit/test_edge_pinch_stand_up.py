"""The hinged tool stands up on its far end (``edge_geometry.pivot_step`` and ``far_edge``): the hand carries the
ring along the arc about the tool's far edge, so that the far end need not slide over the table."""

from __future__ import annotations

import numpy as np
import pytest

from gendex.solve.edge_geometry import far_edge, pivot_step

TABLE_Z = 0.0


def _arc(pinch, far, axis, step_m=0.005):
    points = [np.asarray(pinch, float)]
    for _ in range(500):
        step = pivot_step(points[-1], far, axis, step_m)
        if step is None:
            break
        points.append(points[-1] + step)
    return np.array(points)


@pytest.mark.parametrize("axis", [[1.0, 0.0, 0.0], [0.94, 0.34, 0.0], [-0.77, 0.64, 0.0]])
def test_the_pinch_point_keeps_its_distance_from_the_far_edge_and_ends_above_it(axis):
    axis = np.asarray(axis)
    far = np.array([0.0, -0.45, TABLE_Z])
    pinch = np.array([0.02, -0.62, 0.0035])
    arc = _arc(pinch, far, axis)
    a = axis / np.linalg.norm(axis)
    r0 = pinch - far
    radius = np.linalg.norm(r0 - (r0 @ a) * a)
    rel = arc - far
    perp = rel - np.outer(rel @ a, a)
    assert np.allclose(np.linalg.norm(perp, axis=1), radius, atol=1e-9)  # a turn about the line through the edge
    assert np.allclose(rel @ a, r0 @ a, atol=1e-9)  # nothing moves along the pinch line
    assert np.all(np.diff(arc[:, 2]) > 0.0)  # it only rises
    assert np.linalg.norm(perp[-1, :2]) < 0.005 * 0.6  # it stops straight above the far edge's line
    assert arc[-1, 2] == pytest.approx(radius, abs=1e-4)
    steps = np.linalg.norm(np.diff(arc, axis=0), axis=1)
    assert np.all(steps <= 0.005 + 1e-9)


def test_no_step_once_the_pinch_point_is_above_the_edge():
    far = np.array([0.0, -0.45, TABLE_Z])
    assert pivot_step(far + [0.0, 0.0, 0.17], far, np.array([1.0, 0.0, 0.0]), 0.005) is None
    # past the top (the tool leaning over the other way) it is brought back, not on
    back = pivot_step(far + [0.0, 0.01, 0.17], far, np.array([1.0, 0.0, 0.0]), 0.005)
    assert back[1] < 0.0


def test_the_far_edge_is_the_tool_s_farthest_point_square_to_the_pinch_line():
    """A bar 20 cm long along +y from its ring at the origin, 2 cm wide: for a pinch line along x its far edge is its
    end; for a line at 45 degrees, the end's corner that reaches furthest square to that line."""
    xs, ys = np.meshgrid([-0.01, 0.01], [0.0, 0.2])
    verts = np.column_stack([xs.ravel(), ys.ravel(), np.zeros(4)])
    verts = np.vstack([verts, verts + [0.0, 0.0, 0.007]])
    ring = np.array([0.0, 0.0, 0.0035])
    along = np.array([0.0, 1.0])
    assert far_edge(verts, ring, np.array([1.0, 0.0, 0.0]), along, TABLE_Z) == pytest.approx([0.0, 0.2, TABLE_Z])
    edge = far_edge(verts, ring, np.array([1.0, 1.0, 0.0]) / np.sqrt(2), along, TABLE_Z)
    h = np.array([-1.0, 1.0]) / np.sqrt(2)  # square to the line, towards the tool
    assert edge[:2] @ h == pytest.approx(max(verts[:, :2] @ h))
    assert edge[2] == TABLE_Z
    # the side comes from `toward`, not from where the vertices lie now (a tool standing up has them on both sides)
    assert far_edge(verts, ring, np.array([1.0, 0.0, 0.0]), -along, TABLE_Z)[1] == pytest.approx(-0.0)
