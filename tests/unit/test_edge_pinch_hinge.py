"""The hinge pinch across a ring past the table's side edge (``gendex/solve/edge_pinch.py``): the table stops at its
edges, the arm keeps a margin from the table top that the hand does not need, and the pads' heights where they
meet the ring while closing."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
import sapien

from gendex.solve.edge_drag import ARM_MARGIN_M
from gendex.solve.edge_geometry import PastEdge
from gendex.solve.edge_pinch import EdgePinch
from gendex.solve.grasp import GraspPlan, PinchLine
from gendex.solve.hand import PAD_RADIUS_M

EDGE_Y, HALF_X = 0.6, 0.8


def _past_edge() -> PastEdge:
    synth = PastEdge.__new__(PastEdge)
    synth.table_z, synth.edge_y, synth.half_x = 0.0, EDGE_Y, HALF_X
    return synth


def test_below_the_table_top_counts_only_over_the_table():
    r = np.full(5, 0.007)
    centres = np.array([[0.0, 0.3, 0.003],     # over the table, dipping into it
                        [0.0, 0.62, -0.01],    # 2 cm past the side edge, below the top: free
                        [0.0, -0.604, 0.0],    # straddling the -y edge: its side still touches the table
                        [0.81, 0.0, -0.02],    # past the front edge
                        [0.0, 0.3, 0.05]])     # well above the table
    gap = _past_edge().table_gap(centres, r)
    assert gap[0] == pytest.approx(-0.004)
    assert np.isinf(gap[1]) and np.isinf(gap[3])
    assert gap[2] == pytest.approx(-0.007)
    assert gap[4] == pytest.approx(0.043)


def _edge_with_spheres(centres: np.ndarray, radii: np.ndarray) -> EdgePinch:
    edge = EdgePinch.__new__(EdgePinch)
    edge.edge_y, edge.half_x = EDGE_Y, HALF_X
    collision = SimpleNamespace(sphere_centres=lambda q: (centres, radii))
    edge.m = SimpleNamespace(collision=collision, env=SimpleNamespace(table_height=0.0))
    return edge


def test_the_arm_keeps_a_margin_from_the_table_top_and_the_hand_may_skim_it():
    radii = np.array([0.05, 0.01])  # an arm sphere, then the hand's
    centres = np.array([[-0.3, 0.2, 0.05 + 2 * ARM_MARGIN_M], [-0.2, 0.55, 0.01 + 0.5 * ARM_MARGIN_M]])
    assert _edge_with_spheres(centres, radii)._out_of_table(np.zeros(6), n_hand=1)
    assert not _edge_with_spheres(centres, radii)._out_of_table(np.zeros(6), n_hand=0)  # were both the arm's
    hanging = centres + [[0.0, 0.0, 0.0], [0.0, 0.08, -0.03]]  # the hand past the edge, below the table top
    assert _edge_with_spheres(hanging, radii)._out_of_table(np.zeros(6), n_hand=1)
    hanging[0, 2] = 0.05 + 0.5 * ARM_MARGIN_M  # the arm within its margin of the table top
    assert not _edge_with_spheres(hanging, radii)._out_of_table(np.zeros(6), n_hand=1)


class _Hand:
    """Pads that close along x from 3 cm outside the line's ends, the index dipping 4 mm on the way in."""

    def pads(self, joints: dict[str, float]) -> np.ndarray:
        t = joints["T"]
        return np.array([[-0.045 + 0.03 * t, 0.0, 0.0], [0.045 - 0.03 * t, 0.0, -0.004 * t]])


def test_the_pads_heights_where_they_reach_the_line_while_closing():
    edge = EdgePinch.__new__(EdgePinch)
    edge.hand = _Hand()
    centre = np.array([0.0, 0.62, 0.0035])
    line = PinchLine(centre - [0.015, 0.0, 0.0], centre + [0.015, 0.0, 0.0], "across")
    plan = GraspPlan("pinch", sapien.Pose(centre), np.array([0.0, 0.0, -1.0]), open_hand={"T": 0.0},
                     closing=(({"T": 1.0}, 14),))
    dz = edge._closing_dz(plan, line)
    # the thumb's pad (9.2 mm) touches at x = -15 - 9.2 mm, which it passes at t = (45 - 24.2) / 30 = 0.69; level
    assert dz[0] == pytest.approx(0.0, abs=1e-9)
    # the index's (7.1 mm) touches at t = (45 - 22.1) / 30 = 0.76, by then 3 mm low (sampled in steps of 1/40)
    t_ff = np.ceil((0.045 - 0.015 - PAD_RADIUS_M["ff"]) / 0.03 * 40) / 40
    assert dz[1] == pytest.approx(-0.004 * t_ff, abs=1e-9)
    assert -0.0035 < dz[1] < -0.0029
