"""The hinge's pinch lines across a wrench's ring (``edge_geometry.hinge_headings``): the fixed headings from square to
the tool, and the line along the table's side edge where the tool lies slanted to it."""

from __future__ import annotations

import numpy as np
import pytest

from gendex.solve.edge_geometry import ALONG_EDGE_MAX_DEG, HANG_HEADINGS_DEG, hinge_headings


def _line_heading(across: float, deg: float) -> float:
    """World heading (degrees, modulo 180) of the pinch line ``deg`` from square to the tool."""
    return float(np.degrees(across + np.radians(deg)) % 180.0)


@pytest.mark.parametrize("across_deg", [30.0, -30.0, 12.0, 50.0, 130.0, -150.0])
def test_a_slanted_tool_gets_the_line_along_the_edge(across_deg):
    across = np.radians(across_deg)
    out = hinge_headings(across)
    assert out[: len(HANG_HEADINGS_DEG)] == HANG_HEADINGS_DEG
    assert len(out) == len(HANG_HEADINGS_DEG) + 1
    extra = out[-1]
    assert abs(extra) <= ALONG_EDGE_MAX_DEG
    assert min(abs(_line_heading(across, extra) - a) for a in (0.0, 180.0)) < 0.1  # along x: the side edge


@pytest.mark.parametrize("across_deg", [0.0, 180.0, 19.0, -41.0, 35.0, 90.0, 70.0, -110.0])
def test_no_extra_line_near_a_fixed_one_or_far_from_square(across_deg):
    """Within 5 degrees of a fixed heading the line along the edge is already tried; more than
    ``ALONG_EDGE_MAX_DEG`` from square (a tool lying along the edge) it is not a hinge the tool turns about."""
    assert hinge_headings(np.radians(across_deg)) == HANG_HEADINGS_DEG
