"""Obstacle boxes for a turned part (gendex.solve.collision.rotated_box_cover)."""

import numpy as np
import pytest

from gendex.solve.collision import rotated_box_cover
from gendex.solve.grasp import axis_rotation


def _pose(yaw_rad: float, t=(0.4, 0.1, 0.0)) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = axis_rotation(np.array([0.0, 0.0, 1.0]), yaw_rad)
    m[:3, 3] = t
    return m


def _inside(boxes, pts):
    return np.array([any(np.all(p >= b.lo - 1e-9) and np.all(p <= b.hi + 1e-9) for b in boxes) for p in pts])


def test_an_axis_aligned_frame_gets_one_box_with_the_margin():
    boxes = rotated_box_cover(np.array([0.0, -0.2, 0.0]), np.array([0.02, 0.2, 0.5]), _pose(0.0), 0.01)
    assert len(boxes) == 1
    assert boxes[0].lo == pytest.approx([0.39, -0.11, -0.01]) and boxes[0].hi == pytest.approx([0.43, 0.31, 0.51])


def test_a_swung_door_is_covered_tightly():
    """A 42 cm door slab swung 35 deg: every point of it lies in a box, and the boxes fill far less than the one
    box around the whole wedge the slab spans."""
    lo, hi = np.array([0.0, -0.42, 0.0]), np.array([0.018, 0.0, 0.5])
    pose = _pose(np.radians(35.0))
    boxes = rotated_box_cover(lo, hi, pose, 0.0, piece_m=0.06)
    assert len(boxes) == 7  # cut along the width only: the height stays vertical, the thickness is one piece
    rng = np.random.default_rng(0)
    pts = lo + rng.random((2000, 3)) * (hi - lo)
    world = pts @ pose[:3, :3].T + pose[:3, 3]
    assert _inside(boxes, world).all()
    volume = sum(float(np.prod(b.hi - b.lo)) for b in boxes)
    whole = float(np.prod(world.max(axis=0) - world.min(axis=0)))
    assert volume < 0.3 * whole
    # a point in the wedge beside the slab is free
    beside = pose[:3, :3] @ np.array([-0.1, -0.3, 0.25]) + pose[:3, 3]
    assert not _inside(boxes, beside[None])[0]
