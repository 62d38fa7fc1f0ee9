"""Cheap, conservative collision model of the arm for planning: spheres along its capsules against the table and boxes.

The simulator knows the exact geometry, but a planner asks thousands of "is this configuration free?" questions, so
it gets a model that costs one forward-kinematics pass: every UR10e capsule of :data:`UR10E_LINKS` (and the Shadow
forearm housing) is covered by spheres; a configuration is free when every sphere stays ``margin_m`` above the table
top and outside every obstacle box. Fingers and palm are left out on purpose: they are meant to touch things.

Two kinds of obstacle box: the movable ones a primitive sets for each motion (:meth:`ArmCollisionModel.set_obstacles`:
the objects, an articulated object's links) and the *static* ones that stand for the whole episode
(:meth:`ArmCollisionModel.set_static`: a scene's fixed structures, :func:`structure_obstacles`), which every check
includes whatever a primitive sets.

A held object is attached (:meth:`ArmCollisionModel.attach`) as spheres fixed in the palm frame, so a carry is
planned with the object moving with the hand: it must clear the table, the other objects and the container's rim.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from gendex.solve.ik import ArmIK
from gendex_envs.agents.robot_model import UR10E_LINKS
from gendex_envs.scene_geometry import StructureBox

HOUSING_RADIUS_M = 0.055
"""Radius of the sphere chain covering the Shadow forearm housing (link ``forearm`` to link ``wrist``)."""
STRUCTURE_MARGIN_M = 0.01
"""How much a fixed structure's boxes are inflated as obstacles (as the objects' boxes are)."""


@dataclass(frozen=True)
class Box:
    """Axis-aligned obstacle box in the world frame, already inflated by whatever margin the caller wants."""

    lo: np.ndarray  # [3]
    hi: np.ndarray  # [3]
    name: str = ""


def rotated_box_cover(lo: np.ndarray, hi: np.ndarray, pose: np.ndarray, margin_m: float, piece_m: float = 0.06,
                      name: str = "") -> list[Box]:
    """World-axis-aligned boxes covering the box ``[lo, hi]`` of a frame at ``pose`` [4, 4], each inflated by
    ``margin_m``: one box where the frame is axis-aligned, else the box is cut into pieces of at most ``piece_m``
    along each of its axes that is turned away from the world's (a door swung 30 deg gets a row of small boxes
    along its slab instead of one box over the whole wedge it spans)."""
    rot = pose[:3, :3]
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    cuts = [1 if np.max(np.abs(rot[:, k])) > 0.985 else max(1, int(np.ceil((hi[k] - lo[k]) / piece_m)))
            for k in range(3)]
    out = []
    for idx in np.ndindex(*cuts):
        a = lo + (hi - lo) * np.asarray(idx) / cuts
        b = lo + (hi - lo) * (np.asarray(idx) + 1) / cuts
        corners = np.array([[(a, b)[i][0], (a, b)[j][1], (a, b)[k][2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
        world = corners @ rot.T + pose[:3, 3]
        out.append(Box(world.min(axis=0) - margin_m, world.max(axis=0) + margin_m, name))
    return out


class ArmCollisionModel:
    """Sphere cover of the arm; :meth:`clearance` is the signed free distance (m) of one joint vector."""

    def __init__(self, ik: ArmIK, table_z: float = 0.0, margin_m: float = 0.02, per_capsule: int = 4):
        self.ik = ik
        self.table_z = table_z
        self.margin_m = margin_m
        self.boxes: list[Box] = []
        """Obstacles of the current motion (:meth:`set_obstacles`)."""
        self.static: list[Box] = []
        """Obstacles of the whole episode (:meth:`set_static`: fixed structures), checked along with :attr:`boxes`."""
        t = np.linspace(0.0, 1.0, per_capsule)[:, None]
        self._spheres: list[tuple[str, np.ndarray, np.ndarray]] = []  # (link, local centres [k, 3], radii [k])
        for link in UR10E_LINKS[1:]:  # the shoulder never moves relative to the table
            for p0, p1, r in link.capsules:
                centres = np.asarray(p0, float) + t * (np.asarray(p1, float) - np.asarray(p0, float))
                self._spheres.append((link.name, centres, np.full(len(centres), r)))
        self._housing = t
        self._attached: tuple[np.ndarray, np.ndarray] | None = None  # palm-frame centres [k, 3], radii [k]
        self._hand: tuple[np.ndarray, np.ndarray] | None = None  # the same, for the hand itself
        self._palm = ik.link_names.index("palm")

    def attach(self, world_centres: np.ndarray, radii: np.ndarray, q: np.ndarray) -> None:
        """Fix spheres (world centres at joint vector ``q``) to the palm: they move with the hand from now on."""
        palm = self.ik.fk(q).to_transformation_matrix()
        inv = np.linalg.inv(palm)
        local = np.asarray(world_centres, float) @ inv[:3, :3].T + inv[:3, 3]
        self._attached = (local, np.asarray(radii, float))

    def detach(self) -> None:
        self._attached = None

    def cover_hand(self, palm_centres: np.ndarray | None, radii: np.ndarray | None = None) -> None:
        """Include the hand in the model as spheres (palm-frame centres [k, 3], radii [k]) — e.g. the opened hand
        while the arm brings it next to an object — or leave it out again (``None``, the default: the arm only)."""
        self._hand = None if palm_centres is None else (np.asarray(palm_centres, float), np.asarray(radii, float))

    @property
    def attached(self) -> bool:
        return self._attached is not None

    def set_obstacles(self, boxes: list[Box]) -> None:
        """The obstacles of the motions from now on, besides the static ones (which this leaves in place)."""
        self.boxes = list(boxes)

    def set_static(self, boxes: list[Box]) -> None:
        """Obstacles that stand for the whole episode (a scene's structures); every check includes them."""
        self.static = list(boxes)

    def sphere_centres(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World sphere centres [S, 3] and radii [S] at joint vector ``q``."""
        ik = self.ik
        ik.model.compute_forward_kinematics(np.asarray(q, dtype=np.float64))
        base = ik.base.to_transformation_matrix()
        centres, radii = [], []
        for link, local, r in self._spheres:
            m = base @ ik.model.get_link_pose(ik.link_names.index(link)).to_transformation_matrix()
            centres.append(local @ m[:3, :3].T + m[:3, 3])
            radii.append(r)
        a = (base @ ik.model.get_link_pose(ik.link_names.index("forearm")).to_transformation_matrix())[:3, 3]
        b = (base @ ik.model.get_link_pose(ik.link_names.index("wrist")).to_transformation_matrix())[:3, 3]
        centres.append(a + self._housing * (b - a))
        radii.append(np.full(len(self._housing), HOUSING_RADIUS_M))
        m = base @ ik.model.get_link_pose(self._palm).to_transformation_matrix()
        for palm_spheres in (self._attached, self._hand):
            if palm_spheres is not None:
                centres.append(palm_spheres[0] @ m[:3, :3].T + m[:3, 3])
                radii.append(palm_spheres[1])
        return np.concatenate(centres), np.concatenate(radii)

    def clearance(self, q: np.ndarray) -> float:
        """Smallest distance (m) between a sphere and the table top or a box (of the motion's or the static ones),
        minus the margin; >= 0 means free."""
        c, r = self.sphere_centres(q)
        d = float(np.min(c[:, 2] - r - self.table_z))
        for box in (*self.boxes, *self.static):
            gap = np.maximum(np.maximum(box.lo - c, c - box.hi), 0.0)
            d = min(d, float(np.min(np.linalg.norm(gap, axis=1) - r)))
        return d - self.margin_m

    def is_free(self, q: np.ndarray) -> bool:
        return self.clearance(q) >= 0.0


def box_spheres(lo: np.ndarray, hi: np.ndarray, shrink_m: float = 0.01, cell_m: float = 0.02
                ) -> tuple[np.ndarray, np.ndarray]:
    """Spheres covering a held object's box (shrunk a little: the fingers wrap it): [k, 3] centres, [k] radii.
    Seen from above the box is cut into cells about as wide as it is tall (at least ``cell_m``), each covered by
    a column of spheres as wide as the cell's diagonal: one column for an object at least as tall as it is wide; a
    layer of small spheres for a flat one (one ball as wide as a tuna can's diagonal would hang 3 cm below it)."""
    size = np.maximum(hi - lo - 2 * shrink_m, 1e-3)
    n = np.maximum(1, np.ceil(size[:2] / max(float(size[2]), cell_m) - 1e-9)).astype(int)
    cell = size[:2] / n
    r_in = float(min(cell)) / 2
    nz = max(1, int(np.ceil(size[2] / (2 * r_in))))
    z = np.linspace(lo[2] + shrink_m + r_in, hi[2] - shrink_m - r_in, nz) if nz > 1 else \
        np.array([(lo[2] + hi[2]) / 2])
    xs, ys = (lo[k] + shrink_m + cell[k] * (np.arange(n[k]) + 0.5) for k in range(2))
    pts = np.stack(np.meshgrid(xs, ys, z, indexing="ij"), axis=-1).reshape(-1, 3)
    return pts, np.full(len(pts), float(np.linalg.norm(cell) / 2))


def structure_obstacles(boxes: Iterable[StructureBox], margin_m: float = STRUCTURE_MARGIN_M) -> list[Box]:
    """Obstacle boxes of a scene's fixed structures (:func:`gendex_envs.scene_geometry.structure_boxes`), inflated
    by ``margin_m``; a structure turned off the world's axes is covered by pieces (:func:`rotated_box_cover`)."""
    out = []
    for b in boxes:
        half = np.asarray(b.size_m, dtype=float) / 2
        out += rotated_box_cover(-half, half, b.pose, margin_m, name=f"structure:{b.structure}")
    return out
