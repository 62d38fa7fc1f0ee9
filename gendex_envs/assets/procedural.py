"""Pure-geometry building blocks for the procedural object library (no simulator, no I/O).

Every generator in :mod:`gendex_envs.assets.procedural_shapes` assembles a :class:`Parts` in a working frame
(metres, z up) from the helpers below and hands it to :func:`finish`, which moves it into the asset frame of
:mod:`gendex_envs.assets.manifest` (origin at the bottom centre of the bounding box), rounds every coordinate
to 6 decimals (so the written files are exact and byte-stable) and turns each collision point cloud into its
convex hull.

Collision geometry is convex *by construction*: each hull is the convex hull of a point set that samples one
convex piece of the solid (a band of a solid of revolution whose radius is concave in z, one angular wedge of
one profile segment of a thin vessel wall, one segment of a swept tube, a box, an ellipsoid...). Concave
objects are therefore decomposed exactly and deterministically, without any approximate decomposition tool.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, field

import numpy as np
import trimesh

MAX_HULL_FACES = 255
"""PhysX keeps at most 255 vertices and 255 polygons per convex mesh and silently simplifies larger hulls (a
162-vertex icosphere loses its poles); every hull stays at or below 255 triangles, so it is used as written."""
DECIMALS = 6

SOURCE_REVOLVE = "gendex procedural (trimesh revolve)"
SOURCE_PRIMITIVES = "gendex procedural (trimesh primitives)"
SOURCE_TUBE = "gendex procedural (swept tube)"


@dataclass
class ProceduralShape:
    """One finished object in its asset frame: visual mesh + convex collision hulls + physical metadata."""

    id: str
    category: str
    tags: tuple[str, ...]
    mass_kg: float
    friction: float
    rgba: tuple[float, float, float, float]
    visual: trimesh.Trimesh
    hulls: list[trimesh.Trimesh]
    source: str
    params: dict[str, float | str] = field(default_factory=dict)
    files_of: str = ""
    """The id whose mesh files this shape uses (a colour variant: its base's), or empty for its own."""

    @property
    def volume_m3(self) -> float:
        """Sum of the hull volumes (overlaps counted twice; used only to turn mass into density)."""
        return float(sum(h.volume for h in self.hulls))

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3) axis-aligned bounds of the visual mesh in the asset frame."""
        return self.visual.bounds


@dataclass
class Parts:
    """Accumulator of visual meshes and collision point clouds in a working frame (transformable as a whole)."""

    visuals: list[trimesh.Trimesh] = field(default_factory=list)
    hulls: list[np.ndarray] = field(default_factory=list)
    anchors: dict[str, np.ndarray] = field(default_factory=dict)
    """Named points (e.g. the cavity axis) that follow every transform and end up in the asset frame."""

    def add(self, visual: trimesh.Trimesh | None = None, hulls=()) -> Parts:
        if visual is not None:
            self.visuals.append(visual)
        self.hulls.extend(np.asarray(h, dtype=np.float64).reshape(-1, 3) for h in hulls)
        return self

    def convex(self, points, hull_points=None, faceted: bool = False) -> Parts:
        """A convex piece: its visual is the hull of ``points``, its collision the hull of ``hull_points``.
        ``faceted`` gives every face its own vertices (flat shading for boxes and prisms)."""
        points = np.asarray(points, dtype=np.float64)
        visual = hull_mesh(points)
        if faceted:
            visual = trimesh.Trimesh(visual.triangles.reshape(-1, 3), np.arange(3 * len(visual.faces)).reshape(-1, 3),
                                     process=False)
        return self.add(visual, [points if hull_points is None else hull_points])

    def extend(self, other: Parts) -> Parts:
        self.visuals += other.visuals
        self.hulls += other.hulls
        self.anchors.update(other.anchors)
        return self

    def transform(self, matrix) -> Parts:
        matrix = np.asarray(matrix, dtype=np.float64)
        for v in self.visuals:
            v.apply_transform(matrix)
        self.hulls = [trimesh.transform_points(h, matrix) for h in self.hulls]
        self.anchors = {k: trimesh.transform_points(p.reshape(1, 3), matrix)[0] for k, p in self.anchors.items()}
        return self


def rng_for(name: str) -> np.random.Generator:
    """A generator seeded from the asset id (crc32, so identical across runs and machines)."""
    return np.random.default_rng(zlib.crc32(name.encode()))


def _round(a: np.ndarray) -> np.ndarray:
    return np.round(np.asarray(a, dtype=np.float64), DECIMALS) + 0.0  # + 0.0 turns -0.0 into 0.0


def hull_mesh(points) -> trimesh.Trimesh:
    """Convex hull of a point cloud as a watertight, outward-wound mesh."""
    return trimesh.convex.convex_hull(np.asarray(points, dtype=np.float64))


def finish(parts: Parts, *, id: str, category: str, tags, mass_kg: float, friction: float, rgba, source: str,
           params: dict | None = None) -> ProceduralShape:
    """Move ``parts`` into the asset frame (bbox footprint centred on the origin, lowest visual point at z = 0),
    round coordinates, build the hulls; anchors are recorded in ``params`` as ``<name>_x/_y/_z``."""
    visual = trimesh.util.concatenate(parts.visuals) if len(parts.visuals) > 1 else parts.visuals[0].copy()
    lo, hi = visual.bounds
    offset = -np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]])
    visual = trimesh.Trimesh(_round(visual.vertices + offset), visual.faces, process=False)
    hulls = []
    for k, pts in enumerate(parts.hulls):
        hull = hull_mesh(_round(np.unique(pts, axis=0) + offset))
        if len(hull.faces) > MAX_HULL_FACES:
            raise ValueError(f"{id}: hull {k} has {len(hull.faces)} > {MAX_HULL_FACES} faces")
        hulls.append(hull)
    out = {k: (round(v, DECIMALS) if isinstance(v, float) else v) for k, v in (params or {}).items()}
    for name, p in parts.anchors.items():
        for axis, value in zip("xyz", _round(p + offset), strict=True):
            out[f"{name}_{axis}"] = float(value)
    return ProceduralShape(id=id, category=category, tags=tuple(tags), mass_kg=float(mass_kg),
                           friction=float(friction), rgba=tuple(float(c) for c in rgba), visual=visual,
                           hulls=hulls, source=source, params=out)


# ------------------------------------------------------------------------------------------------ transforms
def rot(axis: str, degrees: float) -> np.ndarray:
    """4x4 rotation about a principal axis."""
    vec = {"x": [1, 0, 0], "y": [0, 1, 0], "z": [0, 0, 1]}[axis]
    return trimesh.transformations.rotation_matrix(np.radians(degrees), vec)


def move(points, offset) -> np.ndarray:
    return np.asarray(points, dtype=np.float64) + np.asarray(offset, dtype=np.float64)


def wobble(rng: np.random.Generator, amp: float, centre=(0.0, 0.0, 0.0)):
    """A smooth, low-frequency asymmetry as a function of points: radial scale about the vertical axis through
    ``centre`` by 1 + amp * (lobe(theta) + oval(theta)); convexity preserving for small amp. Apply the same
    returned function to a visual and its hull points so they stay consistent."""
    a1, a2 = rng.uniform(0.4, 1.0, 2)
    p1, p2 = rng.uniform(0, 2 * np.pi, 2)
    c = np.asarray(centre, dtype=np.float64)

    def apply(points) -> np.ndarray:
        p = np.asarray(points, dtype=np.float64) - c
        theta = np.arctan2(p[:, 1], p[:, 0])
        f = 1 + amp * (a1 * np.cos(theta - p1) + 0.5 * a2 * np.cos(2 * (theta - p2)))
        return np.column_stack([p[:, 0] * f, p[:, 1] * f, p[:, 2]]) + c

    return apply


def cyl_between(p0, p1, r0: float, r1: float | None = None, n: int = 16, phase: float = 0.0) -> np.ndarray:
    """Samples of a (frustum) cylinder from p0 to p1 at any orientation. For a non-vertical axis, ring angle 0
    points along +z-ish and with n divisible by 4 (phase 0) a vertex lies exactly at the bottom."""
    p0, p1 = np.asarray(p0, dtype=np.float64), np.asarray(p1, dtype=np.float64)
    a = (p1 - p0) / np.linalg.norm(p1 - p0)
    ref = np.array([0.0, 0.0, 1.0]) if abs(a[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    v = ref - a * (a @ ref)
    v /= np.linalg.norm(v)
    u = np.cross(v, a)
    t = phase + 2 * np.pi * np.arange(n) / n
    ring = np.outer(np.sin(t), u) + np.outer(np.cos(t), v)
    return np.vstack([p0 + r0 * ring, p1 + (r0 if r1 is None else r1) * ring])


# ------------------------------------------------------------------------------------------------ primitives
def box_pts(size, centre=(0.0, 0.0, 0.0)) -> np.ndarray:
    """The 8 corners of an axis-aligned box."""
    corners = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
    return move(corners * np.asarray(size, dtype=np.float64), centre)


def rounded_box_pts(size, radius: float, centre=(0.0, 0.0, 0.0), subdiv: int = 1) -> np.ndarray:
    """A box with rounded edges and corners (Minkowski sum of a smaller box and a sphere), sampled."""
    sphere = trimesh.creation.icosphere(subdivisions=subdiv, radius=radius).vertices
    inner = box_pts(np.asarray(size, dtype=np.float64) - 2 * radius)
    return move((inner[:, None, :] + sphere[None, :, :]).reshape(-1, 3), centre)


def sphere_pts(n: int = 126) -> np.ndarray:
    """Unit-sphere samples: both poles plus an ``n``-point Fibonacci spiral (even coverage, few vertices: with
    n = 126 the hull has 252 triangles, the most PhysX keeps unsimplified)."""
    i = np.arange(n)
    z = 1 - 2 * (i + 0.5) / n
    r = np.sqrt(1 - z * z)
    phi = i * np.pi * (3 - np.sqrt(5))
    return np.vstack([[0.0, 0.0, -1.0], np.column_stack([r * np.cos(phi), r * np.sin(phi), z]), [0.0, 0.0, 1.0]])


def ellipsoid_pts(radii, centre=(0.0, 0.0, 0.0), subdiv: int | None = None, flat_z: float | None = None,
                  n: int = 126) -> np.ndarray:
    """Ellipsoid samples: icosphere vertices (``subdiv``, for visuals) or a Fibonacci sphere of ``n`` points
    (default, for hulls) scaled to ``radii``; ``flat_z`` (relative to the centre) flattens everything below it."""
    unit = sphere_pts(n) if subdiv is None else trimesh.creation.icosphere(subdivisions=subdiv).vertices
    p = unit * np.asarray(radii, dtype=np.float64)
    if flat_z is not None:
        p[:, 2] = np.maximum(p[:, 2], flat_z)
    return move(p, centre)


def prism_pts(poly_xy, z0: float, z1: float) -> np.ndarray:
    """A vertical prism over a 2-D polygon (its hull is the prism over the polygon's hull)."""
    poly = np.asarray(poly_xy, dtype=np.float64)
    return np.vstack([np.column_stack([poly, np.full(len(poly), z)]) for z in (z0, z1)])


def annulus_sector_pts(r_in: float, r_out: float, a0: float, a1: float, z0: float, z1: float,
                       n: int = 3) -> np.ndarray:
    """A flat ring sector (angles in radians) sampled at ``n`` angles, for C-shaped and ring-shaped parts."""
    t = np.linspace(a0, a1, n)
    ring = [np.column_stack([r * np.cos(t), r * np.sin(t), np.full(n, z)]) for r in (r_in, r_out) for z in (z0, z1)]
    return np.vstack(ring)


def ring_hulls(r_in: float, r_out: float, z0: float, z1: float, a0: float = 0.0, a1: float = 2 * np.pi,
               pieces: int = 8, overlap: float = 0.1) -> list[np.ndarray]:
    """A ring (or ring sector) split into ``pieces`` slightly overlapping convex sectors."""
    step = (a1 - a0) / pieces
    closed = np.isclose(a1 - a0, 2 * np.pi)
    out = []
    for k in range(pieces):
        lo = a0 + k * step - (overlap * step if closed or k > 0 else 0.0)
        hi = a0 + (k + 1) * step + (overlap * step if closed or k < pieces - 1 else 0.0)
        out.append(annulus_sector_pts(r_in, r_out, lo, hi, z0, z1, n=4))
    return out


# ------------------------------------------------------------------------------------------------ revolution
def revolve_mesh(profile, sections: int = 48) -> trimesh.Trimesh:
    """Solid of revolution about z of a closed (r, z) profile running from the axis, outward, back to the axis
    (counter-clockwise in the r-z plane, so the mesh is watertight with outward normals)."""
    mesh = trimesh.creation.revolve(np.asarray(profile, dtype=np.float64), sections=sections)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def revolve_pts(profile, angles) -> np.ndarray:
    """Each (r, z) profile point placed at each angle (radians)."""
    prof = np.asarray(profile, dtype=np.float64)
    ang = np.asarray(angles, dtype=np.float64)
    x = prof[None, :, 0] * np.cos(ang)[:, None]
    y = prof[None, :, 0] * np.sin(ang)[:, None]
    z = np.broadcast_to(prof[None, :, 1], x.shape)
    return np.column_stack([x.ravel(), y.ravel(), z.ravel()])


def revolved_solid(profile, splits=(), sections: int = 48, hull_sections: int = 16):
    """A solid of revolution: (visual mesh, hull point clouds).

    ``profile`` runs from (0, z_bottom) to (0, z_top). ``splits`` are profile indices where the solid is cut into
    bands; each band must have a radius concave in z (dome, cylinder, cone...) so its hull is the band itself.
    """
    prof = np.asarray(profile, dtype=np.float64)
    cuts = [0, *splits, len(prof) - 1]
    angles = 2 * np.pi * np.arange(hull_sections) / hull_sections
    hulls = []
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        band = prof[a:b + 1]
        axis = np.array([[0.0, band[0, 1]], [0.0, band[-1, 1]]])
        hulls.append(revolve_pts(np.vstack([band, axis]), angles))
    return revolve_mesh(prof, sections), hulls


def _normals_out(poly: np.ndarray) -> np.ndarray:
    """Outward (away from the axis / downward at the bottom) unit normals at the vertices of an (r, z) polyline
    that goes up the outside of a vessel."""
    d = np.gradient(poly, axis=0)
    n = np.column_stack([d[:, 1], -d[:, 0]])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def _arc(p0, p1, n: int = 5) -> np.ndarray:
    """Semicircle from p0 to p1 (r-z plane) bulging to the right of p0->p1: from the outer to the inner rim point
    of a wall that rises, it rounds off the rim upward."""
    p0, p1 = np.asarray(p0), np.asarray(p1)
    c, half = (p0 + p1) / 2, (p0 - p1) / 2
    perp = np.array([-half[1], half[0]])
    t = np.linspace(0, np.pi, n)[1:-1]
    return c + np.outer(np.cos(t), half) + np.outer(np.sin(t), perp)


def vessel(outer, wall: float, floor: float, *, wall_from: int = 1, groups: int = 1, wedges: int = 16,
           sections: int = 48, base_splits=(), overlap: float = 0.12):
    """A thin-walled open vessel (cup, bowl, plate...) and its exact convex decomposition.

    ``outer``: (r, z) outside profile from (0, 0) on the axis, along the bottom and up to the rim. The wall is
    the outer profile offset inward by ``wall`` (along its normals); the cavity floor is at z = ``floor``.
    Collision: the solid base (z <= floor, cut into bands at ``base_splits`` z values, each concave) plus, for
    the wall ribs ``outer[wall_from:]`` split into ``groups`` profile segments, ``wedges`` angular wedges per
    segment, each the hull of its inner and outer rib points at three angles, overlapping its neighbours by
    ``overlap`` of a wedge so no gap opens between them.

    Returns (visual mesh, hull point clouds, info) with info = floor_z, top_z and seals: one (r, z) point of the
    wall's mid-surface per segment (tests sweep it around the axis to prove the wedges leave no gap).
    """
    out_p = np.asarray(outer, dtype=np.float64)
    inner = out_p - wall * _normals_out(out_p)
    # the cavity side of the profile: inner points above the floor, joined to the floor at z = floor
    keep = np.nonzero(inner[:, 1] > floor + 1e-9)[0]
    k0 = keep[0]
    a, b = inner[k0 - 1], inner[k0]
    floor_pt = a + (b - a) * (floor - a[1]) / (b[1] - a[1])
    rim = _arc(out_p[-1], inner[-1])
    profile = np.vstack([out_p, rim, inner[k0:][::-1], floor_pt, [0.0, floor]])
    visual = revolve_mesh(profile, sections)

    # solid base: the outer profile up to z = floor, closed along the floor
    j = int(np.searchsorted(out_p[:, 1], floor))  # outer z is non-decreasing
    oa, ob = out_p[j - 1], out_p[min(j, len(out_p) - 1)]
    r_floor = oa[0] if ob[1] == oa[1] else oa[0] + (ob[0] - oa[0]) * (floor - oa[1]) / (ob[1] - oa[1])
    base = [p for p in out_p[:j] if p[1] < floor] + [[r_floor, floor], [0.0, floor]]
    base = np.asarray(base)
    for zs in base_splits:
        base = _insert_z(base, zs)
    split_idx = [int(np.nonzero(np.isclose(base[:, 1], zs) & (base[:, 0] > 0))[0][0]) for zs in base_splits]
    hulls = revolved_solid(base, split_idx, hull_sections=24)[1]

    # wall wedges
    ribs = list(range(wall_from, len(out_p)))
    bounds = np.linspace(0, len(ribs) - 1, groups + 1).round().astype(int)
    step = 2 * np.pi / wedges
    for g in range(groups):
        idx = ribs[bounds[g]:bounds[g + 1] + 1]
        seg = np.vstack([out_p[idx], inner[idx]] + ([rim] if g == groups - 1 else []))
        for w in range(wedges):
            ang = np.linspace(w * step - overlap * step, (w + 1) * step + overlap * step, 3)
            hulls.append(revolve_pts(seg, ang))
    # one probe point per profile segment: the wall's mid-surface half-way between the segment's end ribs
    seals = [(out_p[ribs[a]] + inner[ribs[a]] + out_p[ribs[b]] + inner[ribs[b]]) / 4
             for a, b in zip(bounds[:-1], bounds[1:], strict=True)]
    info = {"floor_z": float(floor), "top_z": float(out_p[-1, 1]), "seals": seals}
    return visual, hulls, info


def _insert_z(profile: np.ndarray, z: float) -> np.ndarray:
    """Insert the point where the profile first crosses height z (if no vertex is already there)."""
    if np.any(np.isclose(profile[:, 1], z) & (profile[:, 0] > 0)):
        return profile
    for i in range(len(profile) - 1):
        (r0, z0), (r1, z1) = profile[i], profile[i + 1]
        if (z0 - z) * (z1 - z) < 0:
            pt = [r0 + (r1 - r0) * (z - z0) / (z1 - z0), z]
            return np.vstack([profile[:i + 1], pt, profile[i + 1:]])
    raise ValueError(f"profile never crosses z={z}")


# ------------------------------------------------------------------------------------------------ swept tubes
def tube(path, half_w, half_h, normal=(0.0, 0.0, 1.0), n_around: int = 12, hull_every: int = 2,
         closed: bool = False, section=None):
    """A tube swept along a 3-D polyline with an elliptic cross-section (half sizes ``half_w`` in the plane of
    the path, ``half_h`` along ``normal``; scalars or per-point arrays). ``section(phi)`` optionally modulates
    the radius (e.g. banana ridges). Returns (visual mesh, hull point clouds), one hull per ``hull_every`` path
    segments (consecutive hulls share a cross-section ring, so the chain has no gaps)."""
    path = np.asarray(path, dtype=np.float64)
    n = len(path)
    hw = np.broadcast_to(np.asarray(half_w, dtype=np.float64), (n,))
    hh = np.broadcast_to(np.asarray(half_h, dtype=np.float64), (n,))
    tang = np.roll(path, -1, 0) - np.roll(path, 1, 0) if closed else np.gradient(path, axis=0)
    tang /= np.linalg.norm(tang, axis=1, keepdims=True)
    up = np.asarray(normal, dtype=np.float64)
    binorm = up - tang * (tang @ up)[:, None]
    binorm /= np.linalg.norm(binorm, axis=1, keepdims=True)
    side = np.cross(binorm, tang)
    phi = 2 * np.pi * np.arange(n_around) / n_around
    mod = np.ones(n_around) if section is None else np.asarray(section(phi), dtype=np.float64)
    rings = (path[:, None, :] + (hw[:, None] * np.cos(phi) * mod)[..., None] * side[:, None, :]
             + (hh[:, None] * np.sin(phi) * mod)[..., None] * binorm[:, None, :])
    verts = rings.reshape(-1, 3)
    faces = []
    segs = n if closed else n - 1
    for i in range(segs):
        a, b = i * n_around, ((i + 1) % n) * n_around
        for j in range(n_around):
            j1 = (j + 1) % n_around
            faces += [[a + j, b + j, b + j1], [a + j, b + j1, a + j1]]
    if not closed:
        verts = np.vstack([verts, path[0], path[-1]])
        c0, c1 = len(verts) - 2, len(verts) - 1
        last = (n - 1) * n_around
        for j in range(n_around):
            j1 = (j + 1) % n_around
            faces += [[c0, j1, j], [c1, last + j, last + j1]]
    mesh = trimesh.Trimesh(verts, np.asarray(faces), process=False)
    if mesh.volume < 0:
        mesh.invert()
    hulls = []
    for i in range(0, segs, hull_every):
        idx = [(i + k) % n for k in range(min(hull_every, segs - i) + 1)]
        hulls.append(rings[idx].reshape(-1, 3))
    return mesh, hulls
