"""Point-in-hull tests for the procedural asset checks (tests/unit/test_procedural.py, test_hanging.py,
test_pouring.py)."""

from __future__ import annotations

import numpy as np


def inside_hulls(hulls, points, tol: float = 0.0) -> np.ndarray:
    """[P] which points lie in (or within ``tol`` of) at least one convex hull (half-space test on its faces)."""
    points = np.atleast_2d(points)
    hit = np.zeros(len(points), dtype=bool)
    for h in hulls:
        d = np.einsum("pfk,fk->pf", points[:, None, :] - h.triangles[None, :, 0, :], h.face_normals)
        hit |= np.all(d <= tol, axis=1)
    return hit
