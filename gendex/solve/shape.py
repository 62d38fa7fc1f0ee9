"""What a rigid object's collision geometry looks like to a grasp planner: convex parts, rays, distances, extents.

:class:`ObjectShape` is read from the live PhysX collision shapes of a built object (exactly what the simulator
collides, whatever asset it came from) once, in the body frame; :meth:`ObjectShape.posed` places it at the body's
current pose. A :class:`PosedShape` answers the questions grasp synthesis asks:

* :meth:`~PosedShape.ray_intervals` — where a line enters and leaves material (a solid object gives one interval,
  the two walls of a bowl two): the antipodal contact pairs of a pinch;
* :meth:`~PosedShape.signed_distance` — how far points are from the surface (negative inside), for the kinematic
  check that an open hand does not already touch the object before it closes;
* :meth:`~PosedShape.footprint` — the centre, long axis and extents of the object seen from above, and
  :meth:`~PosedShape.extent_along` — how thick it is along a direction.

Every convex part is kept as its half-spaces ``n · x + b <= 0``, so a ray and a point cost a few matrix products.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, QhullError


def _sphere_directions(n: int = 160) -> np.ndarray:
    """[n, 3] unit vectors spread evenly over the sphere (a Fibonacci lattice)."""
    k = np.arange(n) + 0.5
    z = 1.0 - 2.0 * k / n
    phi = np.pi * (1.0 + 5.0 ** 0.5) * k
    r = np.sqrt(1.0 - z * z)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


SUPPORT_DIRECTIONS = _sphere_directions()
"""Directions of the extra supporting planes each part keeps for :meth:`PosedShape.signed_distance`: beside an edge
or a corner the faces' planes alone can place a point far nearer than it is (beside a fork handle's thin tilted
segments: at 52 % of the exact distance); with these planes the bound stays at 74-100 % of it there
(``tests/sim/test_grasp_synthesis.py``)."""


@dataclass(frozen=True)
class ConvexPart:
    """One convex part: its vertices [k, 3] and half-spaces (unit normals [f, 3], offsets [f]), inside where
    ``normals @ x + offsets <= 0``; ``support`` adds supporting planes along :data:`SUPPORT_DIRECTIONS` (the same
    form), used only for distances."""

    vertices: np.ndarray
    normals: np.ndarray
    offsets: np.ndarray
    support: np.ndarray | None = None
    """[D] offsets of the planes ``SUPPORT_DIRECTIONS @ x + support <= 0`` through the part's extreme vertices,
    in the frame the part's normals are given in (:meth:`transformed` keeps it consistent)."""
    rotation: np.ndarray | None = None
    """[3, 3] rotation applied to :data:`SUPPORT_DIRECTIONS` (None: identity)."""

    @classmethod
    def of_points(cls, points: np.ndarray) -> ConvexPart | None:
        pts = np.asarray(points, dtype=np.float64)
        if len(pts) < 4:
            return None
        try:
            hull = ConvexHull(pts)
        except QhullError:  # flat or degenerate part: thicken it a little so it still has an inside
            jitter = np.random.default_rng(0).normal(scale=1e-4, size=pts.shape)
            try:
                hull = ConvexHull(np.concatenate([pts, pts + jitter]))
            except QhullError:
                return None
        vertices = hull.points[hull.vertices]
        return cls(vertices, hull.equations[:, :3], hull.equations[:, 3],
                   -np.max(vertices @ SUPPORT_DIRECTIONS.T, axis=0))

    def volume_centroid(self) -> tuple[float, np.ndarray]:
        """Volume and centroid of the part (a fan of tetrahedra from its vertices' mean)."""
        try:
            hull = ConvexHull(self.vertices)
        except QhullError:
            return 0.0, self.vertices.mean(axis=0)
        o = self.vertices.mean(axis=0)
        tri = self.vertices[hull.simplices]  # [F, 3, 3]
        vols = np.abs(np.einsum("ij,ij->i", tri[:, 0] - o, np.cross(tri[:, 1] - o, tri[:, 2] - o))) / 6.0
        total = float(vols.sum())
        if total <= 0.0:
            return 0.0, o
        return total, (vols[:, None] * (tri.sum(axis=1) + o) / 4.0).sum(axis=0) / total

    def transformed(self, m: np.ndarray) -> ConvexPart:
        rot, t = m[:3, :3], m[:3, 3]
        normals = self.normals @ rot.T
        support, rotation = None, None
        if self.support is not None:
            rotation = rot if self.rotation is None else rot @ self.rotation
            support = self.support - (SUPPORT_DIRECTIONS @ rotation.T) @ t
        return ConvexPart(self.vertices @ rot.T + t, normals, self.offsets - normals @ t, support, rotation)

    def distance(self, pts: np.ndarray) -> np.ndarray:
        """[P] lower bound of the distance of points [P, 3] to the part (negative inside): the largest over its
        face planes and its supporting planes."""
        d = np.max(pts @ self.normals.T + self.offsets, axis=1)
        if self.support is not None:
            dirs = SUPPORT_DIRECTIONS if self.rotation is None else SUPPORT_DIRECTIONS @ self.rotation.T
            d = np.maximum(d, np.max(pts @ dirs.T + self.support, axis=1))
        return d


class ObjectShape:
    """Convex parts of one rigid body in its own frame (see the module docstring)."""

    def __init__(self, parts: list[ConvexPart]):
        if not parts:
            raise ValueError("an object shape needs at least one convex part")
        self.parts = parts

    @classmethod
    def of_actor(cls, actor) -> ObjectShape:
        """The shape of a ManiSkill ``Actor`` (first sub-scene) from its PhysX collision shapes."""
        from gendex_envs.assets.bounds import shape_points
        from gendex_envs.physx import px_bodies

        parts = []
        for shape in px_bodies(actor)[0].collision_shapes:
            m = shape.local_pose.to_transformation_matrix()
            part = ConvexPart.of_points(shape_points(shape) @ m[:3, :3].T + m[:3, 3])
            if part is not None:
                parts.append(part)
        return cls(parts)

    def posed(self, pose_matrix: np.ndarray) -> PosedShape:
        """The shape placed by a 4x4 body-to-world transform."""
        return PosedShape([p.transformed(np.asarray(pose_matrix, dtype=np.float64)) for p in self.parts])


@dataclass(frozen=True)
class Footprint:
    """The object seen from above: centre (x, y), unit long axis (x, y), extents along and across it, and its
    bottom and top heights."""

    center: np.ndarray
    axis: np.ndarray
    length: float
    width: float
    bottom: float
    top: float

    @property
    def height(self) -> float:
        return self.top - self.bottom

    @property
    def across(self) -> np.ndarray:
        """Unit horizontal direction perpendicular to the long axis."""
        return np.array([-self.axis[1], self.axis[0]])


_MAX, _MIN = np.maximum.reduce, np.minimum.reduce


class PosedShape:
    """An :class:`ObjectShape` at one pose, in world coordinates."""

    def __init__(self, parts: list[ConvexPart]):
        self.parts = parts
        self.vertices = np.concatenate([p.vertices for p in parts])

    @property
    def lo(self) -> np.ndarray:
        return self.vertices.min(axis=0)

    @property
    def hi(self) -> np.ndarray:
        return self.vertices.max(axis=0)

    def ray_intervals(self, origin: np.ndarray, direction: np.ndarray) -> list[tuple[float, float]]:
        """Sorted, merged parameter intervals ``[t_in, t_out]`` where the line ``origin + t * direction`` (t any
        real, ``direction`` unit) is inside material."""
        o, d = np.asarray(origin, float), np.asarray(direction, float)
        spans = []
        # one errstate for all parts and the ufuncs' own reductions: this runs tens of thousands of times a grasp
        # search, where numpy's per-call wrappers cost more than the arithmetic (the same numbers either way)
        with np.errstate(divide="ignore", invalid="ignore"):
            for p in self.parts:
                num = -(p.normals @ o + p.offsets)  # n·(o + t d) + b <= 0  <=>  t (n·d) <= num
                den = p.normals @ d
                t = num / den
                parallel = np.abs(den) < 1e-12
                if (parallel & (num < 0)).any():
                    continue  # parallel to a face and outside it
                t_in = _MAX(t[(den < 0) & ~parallel], initial=-np.inf)
                t_out = _MIN(t[(den > 0) & ~parallel], initial=np.inf)
                if t_in < t_out:
                    spans.append((float(t_in), float(t_out)))
        spans.sort()
        merged: list[tuple[float, float]] = []
        for a, b in spans:
            if merged and a <= merged[-1][1] + 1e-6:
                merged[-1] = (merged[-1][0], max(merged[-1][1], b))
            else:
                merged.append((a, b))
        return merged

    def signed_distance(self, points: np.ndarray) -> np.ndarray:
        """[P] distance of points [P, 3] to the nearest part (negative inside one). Outside, a part's distance is
        taken as its largest distance to a supporting plane (its faces' and :data:`SUPPORT_DIRECTIONS`'): exact in
        front of a face, below the truth near edges and corners (so a collision check with it errs on the safe
        side)."""
        pts = np.atleast_2d(np.asarray(points, float))
        best = np.full(len(pts), np.inf)
        for p in self.parts:
            best = np.minimum(best, p.distance(pts))
        return best

    def centroid(self) -> np.ndarray:
        """[3] volume-weighted centroid of the convex parts: the centre of mass of a uniformly dense object."""
        masses = [p.volume_centroid() for p in self.parts]
        total = sum(v for v, _ in masses)
        if total <= 0.0:
            return self.vertices.mean(axis=0)
        return sum(v * c for v, c in masses) / total

    def footprint(self) -> Footprint:
        """Centre, long axis and extents of the vertices projected on the table (principal axes of the xy hull)."""
        xy = self.vertices[:, :2]
        try:
            hull = xy[ConvexHull(xy).vertices]
        except QhullError:
            hull = xy
        best = None
        for i in range(len(hull)):  # minimum-area rectangle: one side lies along a hull edge
            e = hull[(i + 1) % len(hull)] - hull[i]
            n = np.linalg.norm(e)
            if n < 1e-9:
                continue
            u = e / n
            v = np.array([-u[1], u[0]])
            a, b = hull @ u, hull @ v
            area = (a.max() - a.min()) * (b.max() - b.min())
            if best is None or area < best[0]:
                best = (area, u, v, a, b)
        if best is None:
            u, v = np.array([1.0, 0.0]), np.array([0.0, 1.0])
            a, b = xy @ u, xy @ v
        else:
            _, u, v, a, b = best
        if a.max() - a.min() < b.max() - b.min():  # the long axis first
            u, v, a, b = v, -u, b, -a
        center = u * (a.max() + a.min()) / 2 + v * (b.max() + b.min()) / 2
        return Footprint(center=center, axis=u, length=float(a.max() - a.min()), width=float(b.max() - b.min()),
                         bottom=float(self.vertices[:, 2].min()), top=float(self.vertices[:, 2].max()))

    def extent_along(self, direction: np.ndarray) -> tuple[float, float]:
        """(min, max) of the vertices projected on ``direction``."""
        s = self.vertices @ np.asarray(direction, float)
        return float(s.min()), float(s.max())

    def top_at(self, xy: np.ndarray) -> float | None:
        """Height of the highest material on the vertical line through ``xy``, or None where there is none."""
        spans = self.ray_intervals(np.array([xy[0], xy[1], 0.0]), np.array([0.0, 0.0, 1.0]))
        return spans[-1][1] if spans else None
