"""Geometry of a flat ringed tool at the table's side edge (:mod:`gendex.solve.edge_drag` and
:mod:`gendex.solve.edge_pinch` move it): where its ring is, which way a finger in the ring turns it before the drag, the
pinch lines across the ring, the edge its far end stands up on, and the table top that ends at its edges."""

from __future__ import annotations

import numpy as np

from gendex.solve.grasp import GraspSynthesizer
from gendex.solve.hand import HandModel
from gendex.solve.shape import PosedShape

FLAT_M = 0.012
"""Only objects at most this tall are dragged to the edge."""
RING_MIN_RADIUS_M = 0.006
"""A hole the index fingertip fits in (its end cap, 7.1 mm radius, is narrower at the height of a 7 mm ring;
the wrench's octagonal 15 mm ring is 6.9 mm to its flats)."""
RING_MAX_RADIUS_M = 0.015
"""Larger holes are not looked for (a point that far from all material is beside the tool)."""
RING_ROUND = 1.5
"""A hole is a ring when material surrounds it in every horizontal direction within this many times its radius (a
notch in the outline is open on one side)."""
HANG_HEADINGS_DEG = (0.0, 20.0, -20.0, 40.0, -40.0)
"""Pinch lines through the ring's centre, level with it, in degrees from square to the tool (each both ways round):
square to it, the line crosses the wrench's ring through its centre and the tool turns about it in its own plane.
The line along the edge is tried as well where it is at most :data:`ALONG_EDGE_MAX_DEG` from square: both pads are
then as far past the edge as the ring's centre (a slanted line brings the inner pad over the table top)."""
ALONG_EDGE_MAX_DEG = 60.0
TURN_MAX_RAD = np.radians(90.0)
TURN_MIN_RAD = np.radians(10.0)
"""The turn before the drag (:func:`turn_to_edge`): at most this much either way, and none below the least."""


def find_ring(shape: PosedShape, step_m: float = 0.001) -> np.ndarray | None:
    """World centre [3] (at mid-height) of the widest hole through a flat ``shape`` that a fingertip fits in and
    material surrounds (:data:`RING_MIN_RADIUS_M`, :data:`RING_ROUND`), or None."""
    fp = shape.footprint()
    if fp.height > FLAT_M:
        return None
    z = fp.bottom + fp.height / 2
    side = np.array([-fp.axis[1], fp.axis[0]])
    a = np.arange(-fp.length / 2, fp.length / 2, step_m)
    b = np.arange(-fp.width / 2, fp.width / 2, step_m)
    pts = np.array([[*(fp.center + s * fp.axis + t * side), z] for s in a for t in b])
    sd = shape.signed_distance(pts)
    dirs = [np.array([np.cos(t), np.sin(t), 0.0]) for t in np.linspace(0, 2 * np.pi, 8, endpoint=False)]
    for i in np.argsort(-sd):
        if sd[i] > RING_MAX_RADIUS_M:
            continue  # open table beside the tool, not a hole in it
        if sd[i] < RING_MIN_RADIUS_M:
            return None
        ahead = [[a for a, b in shape.ray_intervals(pts[i], d) if b > 0.0] for d in dirs]
        if all(h and min(h) <= RING_ROUND * sd[i] for h in ahead):
            return pts[i]
    return None


def turn_to_edge(ring: np.ndarray, com: np.ndarray, side: float) -> float:
    """The turn (rad, counter-clockwise seen from above) that points a tool's ring (at ``ring``) straight at the
    table's side edge ``side`` (+1: +y, -1: -y) from its centre of mass (at ``com``): 0 within :data:`TURN_MIN_RAD`,
    else at most :data:`TURN_MAX_RAD` either way."""
    d = np.asarray(ring[:2], float) - np.asarray(com[:2], float)
    want = float((np.arctan2(side, 0.0) - np.arctan2(d[1], d[0]) + np.pi) % (2 * np.pi) - np.pi)
    return float(np.clip(want, -TURN_MAX_RAD, TURN_MAX_RAD)) if abs(want) > TURN_MIN_RAD else 0.0


def pivot_step(pinch: np.ndarray, far: np.ndarray, axis: np.ndarray, step_m: float) -> np.ndarray | None:
    """Offset [3] that moves ``pinch`` (a point on the tool, world) by an arc of ``step_m`` as the tool turns up
    about a line through ``far`` (its far edge on the table) parallel to ``axis`` (the horizontal pinch line), or
    None where ``pinch`` is within half a step of straight above that line: the tool stands up on its far end
    without sliding, held at the top."""
    a = np.array([axis[0], axis[1], 0.0]) / np.linalg.norm(axis[:2])
    r = pinch - far
    base = far + (r @ a) * a  # the pinch point's foot on the pivot line
    h = np.cross(a, [0.0, 0.0, 1.0])
    radius = float(np.linalg.norm(r - (r @ a) * a))
    phi = float(np.arctan2(r[2], r @ h))
    left, dphi = np.pi / 2 - phi if phi <= np.pi / 2 else phi - np.pi / 2, step_m / radius
    if left <= dphi / 2:
        return None
    phi += np.sign(np.pi / 2 - phi) * min(dphi, left)
    return base + radius * (np.cos(phi) * h + np.sin(phi) * np.array([0.0, 0.0, 1.0])) - pinch


def hinge_headings(across: float) -> tuple[float, ...]:
    """Headings (degrees from ``across``, the heading in rad of the horizontal line square to the tool) of the hinge's
    pinch lines: :data:`HANG_HEADINGS_DEG`, and the line along the table's side edge where it is at most
    :data:`ALONG_EDGE_MAX_DEG` from square and not within 5 degrees of one of those."""
    along_edge = float((np.degrees(-across) + 90.0) % 180.0 - 90.0)
    if abs(along_edge) > ALONG_EDGE_MAX_DEG or min(abs(along_edge - h) for h in HANG_HEADINGS_DEG) <= 5.0:
        return HANG_HEADINGS_DEG
    return (*HANG_HEADINGS_DEG, round(along_edge, 1))


def far_edge(verts: np.ndarray, ring: np.ndarray, axis: np.ndarray, toward: np.ndarray, table_z: float) -> np.ndarray:
    """A point [3] of the line, parallel to the pinch line ``axis`` and on the table top (``table_z``), about which a
    tool (its vertices ``verts`` [V, 3], world) turns up when its ring (at ``ring``) is lifted: its farthest edge from
    the ring square to that line, on the side of ``toward`` (a horizontal direction [2] from the ring along the tool
    as it lay: fixed while it stands up, when its vertices come to lie on both sides of the ring)."""
    h = np.cross([axis[0], axis[1], 0.0], [0.0, 0.0, 1.0])
    h *= np.sign(h[:2] @ toward) or 1.0
    h /= np.linalg.norm(h)
    reach = float(np.max(verts @ h) - ring @ h)
    return np.array([*(ring[:2] + reach * h[:2]), table_z])


class PastEdge(GraspSynthesizer):
    """Pinches of a tool overhanging the table's side edge: past the edge the hand may reach below the table top."""

    def __init__(self, hand: HandModel, shape: PosedShape, table_z: float, edge_y: float, half_x: float):
        super().__init__(hand, shape, table_z)
        self.edge_y, self.half_x = edge_y, half_x

    def table_gap(self, centers: np.ndarray, radii: np.ndarray) -> np.ndarray:
        return table_top_gap(centers, radii, self.table_z, self.edge_y, self.half_x)


def table_top_gap(centers: np.ndarray, radii: np.ndarray, table_z: float, edge_y: float, half_x: float) -> np.ndarray:
    """[n] how far each sphere (``centers`` [n, 3], ``radii`` [n]) is above the table top (negative: in it), the top
    a slab ending at ``|y| = edge_y`` and ``|x| = half_x``: inf for a sphere wholly past an edge."""
    off = (np.abs(centers[:, 1]) >= edge_y + radii) | (np.abs(centers[:, 0]) >= half_x + radii)
    return np.where(off, np.inf, centers[:, 2] - radii - table_z)
