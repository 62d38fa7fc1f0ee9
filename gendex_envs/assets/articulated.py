"""Parametric articulated assets built from URDF primitives (box, cylinder, sphere: every collision shape convex).

Each generator is pure: parameters -> :class:`Model`, which renders to URDF text (:meth:`Model.urdf`) and to a
manifest :class:`~gendex_envs.assets.manifest.AssetEntry` (:meth:`Model.entry`). Conventions of every model:

* Asset frame: z up, origin at the bottom centre of the closed model, lowest point z = 0, metres at real scale.
* The front (door, drawer, handle, knob side) faces -x, towards a robot standing at -x. "Left" and "right" are as
  seen from the front, i.e. by a viewer at -x looking along +x: left = +y, right = -y.
* The root link is ``body``; every joint origin has no rotation, so at qpos 0 each link frame is the asset frame
  translated by the joint origins. Positive joint values always open (door swings towards -x, drawer slides to -x,
  lid tilts up, knob turns counter-clockwise as seen from the front).
* Handles are extra shapes on the moving link; ``handle_point_m`` is the grip centre in that link's frame.
* Each link's ``<inertial>``: its mass at the shapes' volume-weighted centroid, with the inertia of a solid box of
  that mass filling the link's collision bounding box.

``python -m gendex_envs.assets.build_articulated`` writes every variant of :data:`VARIANTS` and of
:mod:`gendex_envs.assets.articulated_more`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

from gendex_envs.assets.manifest import AssetEntry, JointEntry

SOURCE = "gendex procedural URDF"
LICENCE = "Apache-2.0"

Vec3 = tuple[float, float, float]
RGBA = tuple[float, float, float, float]

WOOD: RGBA = (0.62, 0.45, 0.30, 1.0)
WHITE: RGBA = (0.90, 0.90, 0.88, 1.0)
STEEL: RGBA = (0.75, 0.75, 0.78, 1.0)
DARK: RGBA = (0.12, 0.12, 0.14, 1.0)
PLASTIC: RGBA = (0.25, 0.45, 0.65, 1.0)
SILVER: RGBA = (0.68, 0.70, 0.73, 1.0)
RED: RGBA = (0.80, 0.15, 0.12, 1.0)
YELLOW: RGBA = (0.95, 0.78, 0.10, 1.0)
GREEN: RGBA = (0.15, 0.62, 0.25, 1.0)

BAR_R = 0.011
"""Default handle-bar radius (Ø 2.2 cm)."""
STANDOFF = 0.04
"""Distance from the mounting surface to a handle bar's axis (clearance 2.9 cm behind a Ø 2.2 cm bar)."""
POST = 0.012
"""Cross-section of the square posts that hold a handle bar."""


def _f(x: float) -> str:
    """Deterministic short float text (7 decimals, no negative zero)."""
    return repr(round(float(x), 7) + 0.0)


def _v(xs) -> str:
    return " ".join(_f(x) for x in xs)


@dataclass(frozen=True)
class Shape:
    """One primitive, used as both collision and visual shape of its link."""

    kind: Literal["box", "cylinder", "sphere"]
    centre: Vec3
    size: Vec3
    """box: full extents; cylinder: (radius, length, 0); sphere: (radius, 0, 0)."""
    axis: Literal["x", "y", "z"] = "z"
    """Cylinder axis (URDF cylinders run along z; other axes get an rpy)."""
    rgba: RGBA = STEEL

    def half_extents(self) -> Vec3:
        if self.kind == "box":
            return tuple(s / 2 for s in self.size)
        if self.kind == "sphere":
            return (self.size[0],) * 3
        r, half = self.size[0], self.size[1] / 2
        return tuple(half if a == self.axis else r for a in "xyz")

    def geometry_xml(self) -> str:
        if self.kind == "box":
            return f'<box size="{_v(self.size)}"/>'
        if self.kind == "sphere":
            return f'<sphere radius="{_f(self.size[0])}"/>'
        return f'<cylinder radius="{_f(self.size[0])}" length="{_f(self.size[1])}"/>'

    def rpy(self) -> Vec3:
        if self.kind == "cylinder" and self.axis == "x":
            return (0.0, math.pi / 2, 0.0)
        if self.kind == "cylinder" and self.axis == "y":
            return (math.pi / 2, 0.0, 0.0)
        return (0.0, 0.0, 0.0)


def box(lo: Vec3, hi: Vec3, rgba: RGBA) -> Shape:
    """Axis-aligned box between corners ``lo`` and ``hi``."""
    centre = tuple((a + b) / 2 for a, b in zip(lo, hi, strict=True))
    return Shape("box", centre, tuple(b - a for a, b in zip(lo, hi, strict=True)), "z", rgba)


def cyl(centre: Vec3, radius: float, length: float, axis: Literal["x", "y", "z"], rgba: RGBA) -> Shape:
    return Shape("cylinder", centre, (radius, length, 0.0), axis, rgba)


def sphere(centre: Vec3, radius: float, rgba: RGBA) -> Shape:
    return Shape("sphere", centre, (radius, 0.0, 0.0), "z", rgba)


def bounds(shapes: list[Shape] | tuple[Shape, ...], offset: Vec3 = (0.0, 0.0, 0.0)) -> tuple[Vec3, Vec3]:
    """Axis-aligned bounds of ``shapes`` translated by ``offset``."""
    lo = [math.inf] * 3
    hi = [-math.inf] * 3
    for s in shapes:
        for i, h in enumerate(s.half_extents()):
            lo[i] = min(lo[i], s.centre[i] + offset[i] - h)
            hi[i] = max(hi[i], s.centre[i] + offset[i] + h)
    return tuple(lo), tuple(hi)


@dataclass(frozen=True)
class Link:
    name: str
    mass: float
    shapes: tuple[Shape, ...]

    com: Vec3 | None = None
    """Centre of mass override (default: volume-weighted centroid of the shapes)."""

    def centroid(self) -> Vec3:
        vols = [s.size[0] * s.size[1] * s.size[2] if s.kind == "box" else
                math.pi * s.size[0] ** 2 * s.size[1] if s.kind == "cylinder" else 4 / 3 * math.pi * s.size[0] ** 3
                for s in self.shapes]
        return tuple(sum(v * s.centre[i] for v, s in zip(vols, self.shapes, strict=True)) / sum(vols) for i in range(3))

    def inertial_xml(self) -> str:
        lo, hi = bounds(self.shapes)
        c = self.com if self.com is not None else self.centroid()
        sx, sy, sz = (b - a for a, b in zip(lo, hi, strict=True))
        m = self.mass
        ixx, iyy, izz = m * (sy * sy + sz * sz) / 12, m * (sx * sx + sz * sz) / 12, m * (sx * sx + sy * sy) / 12
        return (f'  <inertial>\n   <origin xyz="{_v(c)}" rpy="0 0 0"/>\n   <mass value="{_f(m)}"/>\n'
                f'   <inertia ixx="{ixx:.6e}" ixy="0" ixz="0" iyy="{iyy:.6e}" iyz="0" izz="{izz:.6e}"/>\n'
                f'  </inertial>\n')


@dataclass(frozen=True)
class Joint:
    """A movable joint with its semantics; the child link carries the handle."""

    name: str
    type: Literal["revolute", "prismatic"]
    parent: str
    child: str
    origin: Vec3
    """Child link frame in the parent link frame (no rotation)."""
    axis: Vec3
    limits: tuple[float, float]
    closed: float
    open: float
    handle_point: Vec3
    """Grip centre in the child link frame at qpos 0."""
    damping: float = 0.2
    friction: float = 0.02
    """URDF only (SAPIEN's loader ignores it; GenDex applies ``friction_limit``)."""
    effort: float = 50.0
    velocity: float = 3.0
    holds: tuple[Vec3, Vec3] | None = None
    """The space the child link holds things in (a drawer's bin), (low, high) corners in the child link frame."""
    detents: tuple[float, ...] | None = None
    """Rest positions (fractions from closed to open) a spring of stiffness ``spring`` pulls towards (nearest)."""
    spring: float | None = None
    friction_limit: float | None = None  # JointEntry.friction_limit: dry friction GenDex applies


@dataclass(frozen=True)
class Model:
    """One articulated asset: a tree of links rooted at ``links[0]`` plus what the manifest needs."""

    id: str
    category: str
    tags: tuple[str, ...]
    links: tuple[Link, ...]
    joints: tuple[Joint, ...]
    """Movable joints, the main joint first."""
    fixed_base: bool = True
    friction: float = 0.8
    params: dict[str, float | str] = field(default_factory=dict)

    def link_origin(self, name: str) -> Vec3:
        """Link frame position in the asset frame at qpos 0."""
        for j in self.joints:
            if j.child == name:
                p = self.link_origin(j.parent)
                return tuple(a + b for a, b in zip(p, j.origin, strict=True))
        return (0.0, 0.0, 0.0)

    def bounds(self) -> tuple[Vec3, Vec3]:
        """Bounds of all collision shapes at qpos 0 (the closed pose), asset frame."""
        shapes = [Shape(s.kind, tuple(a + b for a, b in zip(s.centre, self.link_origin(link.name), strict=True)),
                        s.size, s.axis)
                  for link in self.links for s in link.shapes]
        return bounds(shapes)

    @property
    def mass(self) -> float:
        return sum(link.mass for link in self.links)

    def urdf(self) -> str:
        out = [f'<?xml version="1.0"?>\n<!-- {SOURCE}: {self.id} ({LICENCE}) -->\n<robot name="{self.id}">\n']
        for link in self.links:
            out.append(f' <link name="{link.name}">\n')
            out.append(link.inertial_xml())
            for k, s in enumerate(link.shapes):
                origin = f'<origin xyz="{_v(s.centre)}" rpy="{_v(s.rpy())}"/>'
                geom = f"<geometry>{s.geometry_xml()}</geometry>"
                out.append(f'  <visual name="{link.name}_{k}">\n   {origin}\n   {geom}\n'
                           f'   <material name="{link.name}_{k}"><color rgba="{_v(s.rgba)}"/></material>\n'
                           f'  </visual>\n')
                out.append(f'  <collision name="{link.name}_{k}">\n   {origin}\n'
                           f'   <geometry>{s.geometry_xml()}</geometry>\n  </collision>\n')
            out.append(" </link>\n")
        for j in self.joints:
            out.append(f' <joint name="{j.name}" type="{j.type}">\n  <parent link="{j.parent}"/>\n'
                       f'  <child link="{j.child}"/>\n  <origin xyz="{_v(j.origin)}" rpy="0 0 0"/>\n'
                       f'  <axis xyz="{_v(j.axis)}"/>\n'
                       f'  <limit lower="{_f(j.limits[0])}" upper="{_f(j.limits[1])}" effort="{_f(j.effort)}" '
                       f'velocity="{_f(j.velocity)}"/>\n'
                       f'  <dynamics damping="{_f(j.damping)}" friction="{_f(j.friction)}"/>\n </joint>\n')
        out.append("</robot>\n")
        return "".join(out)

    def entry(self, urdf_path: str) -> AssetEntry:
        lo, hi = self.bounds()
        r6 = lambda xs: tuple(round(float(x), 6) + 0.0 for x in xs)  # noqa: E731
        joints = tuple(JointEntry(j.name, j.type, r6(j.limits), round(j.closed, 6), round(j.open, 6), j.child,
                                  r6(j.handle_point), None if j.holds is None else (r6(j.holds[0]), r6(j.holds[1])),
                                  None if j.holds is None else r6(j.origin), j.detents, j.spring,
                                  j.friction_limit)
                       for j in self.joints)
        return AssetEntry(id=self.id, category=self.category, kind="articulated", source=SOURCE, licence=LICENCE,
                          tags=("articulated",) + self.tags, bbox_min_m=r6(lo), bbox_max_m=r6(hi),
                          mass_kg=round(self.mass, 6), friction=self.friction,
                          rgba=self.links[0].shapes[0].rgba, urdf=urdf_path, fixed_base=self.fixed_base,
                          joints=joints, params=dict(self.params))


# ---------------------------------------------------------------------------------------------------------- parts


def shell(d: float, w: float, h: float, t: float, rgba: RGBA, open_faces: tuple[str, ...] = ("-x",),
          z0: float = 0.0) -> list[Shape]:
    """Walls (thickness ``t``) of the box x in [-d/2, d/2], y in [-w/2, w/2], z in [z0, h], minus ``open_faces``."""
    x0, x1, y0, y1 = -d / 2, d / 2, -w / 2, w / 2
    walls = {
        "-x": ((x0, y0, z0), (x0 + t, y1, h)), "+x": ((x1 - t, y0, z0), (x1, y1, h)),
        "-y": ((x0, y0, z0), (x1, y0 + t, h)), "+y": ((x0, y1 - t, z0), (x1, y1, h)),
        "-z": ((x0, y0, z0), (x1, y1, z0 + t)), "+z": ((x0, y0, h - t), (x1, y1, h)),
    }
    return [box(lo, hi, rgba) for face, (lo, hi) in walls.items() if face not in open_faces]


def bar_handle(surface_x: float, y: float, z: float, length: float, axis: Literal["y", "z"],
               radius: float = BAR_R, knobs: bool = False) -> tuple[list[Shape], Vec3]:
    """A bar along ``axis`` ``STANDOFF`` in front (-x) of a surface at ``surface_x``, on two posts at its ends.

    Returns the shapes and the grip point (bar centre). ``knobs`` adds spherical end caps (a "knob-bar").
    """
    bx = surface_x - STANDOFF
    shapes = [cyl((bx, y, z), radius, length, axis, STEEL)]
    k = 1 if axis == "y" else 2
    for sign in (-1, 1):
        c = [bx, y, z]
        c[k] += sign * (length / 2 - POST)
        lo = (bx, c[1] - POST / 2, c[2] - POST / 2)
        shapes.append(box(lo, (surface_x + 0.002, c[1] + POST / 2, c[2] + POST / 2), STEEL))
        if knobs:
            e = [bx, y, z]
            e[k] += sign * length / 2
            shapes.append(sphere(tuple(e), radius + 0.004, STEEL))
    return shapes, (bx, y, z)


def tab(front_x: float, z_lo: float, z_hi: float, out: float = 0.03, width: float = 0.05,
        rgba: RGBA = DARK) -> tuple[list[Shape], Vec3]:
    """A flat tab sticking ``out`` in front (-x) of an edge at ``front_x``; returns shapes and its grip centre."""
    s = box((front_x - out, -width / 2, z_lo), (front_x + 0.005, width / 2, z_hi), rgba)
    return [s], (front_x - out / 2, 0.0, (z_lo + z_hi) / 2)


def side_door(body_d: float, w: float, y_lo: float, y_hi: float, z_lo: float, z_hi: float, hinge: str,
              t: float, rgba: RGBA, bar_len: float, bar_z: float, bar_r: float = BAR_R,
              knobs: bool = False) -> tuple[Vec3, Vec3, list[Shape], Vec3]:
    """A door on the front face (x = -body_d/2) covering y in [y_lo, y_hi], z in [z_lo, z_hi], hinged on a vertical
    axis at its ``hinge`` ("left" = +y, "right" = -y) front edge, with a vertical bar 3.5 cm from its free edge at
    height ``bar_z`` (asset frame). Returns (joint origin, axis, door shapes in the door frame, grip point)."""
    del w
    s = -1.0 if hinge == "left" else 1.0  # direction from the hinge to the free edge along y
    hy = y_hi if hinge == "left" else y_lo
    origin = (-body_d / 2 - t, hy, z_lo)
    width = y_hi - y_lo
    slab = box((0.0, min(0.0, s * width), 0.0), (t, max(0.0, s * width), z_hi - z_lo), rgba)
    handle, grip = bar_handle(0.0, s * (width - 0.035), bar_z - z_lo, bar_len, "z", bar_r, knobs)
    return origin, (0.0, 0.0, s), [slab] + handle, grip


def bottom_door(body_d: float, y_half: float, z_lo: float, z_hi: float, t: float, rgba: RGBA,
                bar_len: float) -> tuple[Vec3, list[Shape], Vec3]:
    """A door on the front face hinged along y at its bottom front edge (opens by tilting its top towards -x),
    with a horizontal bar 3.5 cm below its top edge. Hinging at the front face puts the door's centre of mass
    behind the axis, so gravity holds it closed. Returns (joint origin, door shapes, grip point)."""
    origin = (-body_d / 2 - t, 0.0, z_lo)
    h = z_hi - z_lo
    slab = box((0.0, -y_half, 0.0), (t, y_half, h), rgba)
    handle, grip = bar_handle(0.0, 0.0, h - 0.035, bar_len, "y")
    return origin, [slab] + handle, grip


# ------------------------------------------------------------------------------------------------------ generators

DOOR_LIMITS = (0.0, 1.9)
DOOR_OPEN = 1.4


def cabinet(id: str, hinge: Literal["left", "right"], depth: float = 0.40, width: float = 0.42,
            height: float = 0.50, handle: Literal["bar", "knob_bar"] = "bar") -> Model:
    """Wooden cabinet with one shelf and a full-front side-hinged door."""
    d, w, h, t, dt = depth, width, height, 0.015, 0.018
    shelf = box((-d / 2 + 0.02, -w / 2 + t, h / 2 - t / 2), (d / 2 - t, w / 2 - t, h / 2 + t / 2), WOOD)
    body = shell(d, w, h, t, WOOD) + [shelf]
    bar_len = 0.14 if handle == "bar" else 0.10
    origin, axis, door, grip = side_door(d, w, -w / 2, w / 2, 0.002, h - 0.002, hinge, dt, WOOD, bar_len, 0.55 * h,
                                         knobs=handle == "knob_bar")
    return Model(id, "cabinet", ("furniture", "container", "door"),
                 (Link("body", 8.0, tuple(body)), Link("door", 1.5, tuple(door))),
                 (Joint("door_hinge", "revolute", "body", "door", origin, axis, DOOR_LIMITS, 0.0, DOOR_OPEN, grip),),
                 params={"depth": d, "width": w, "height": h, "hinge": hinge, "handle": handle})


def drawer_chest(id: str, n: int, depth: float = 0.40, width: float = 0.45, height: float = 0.50) -> Model:
    """Wooden chest of ``n`` stacked drawers (drawer_0 on top, the main joint), each with a horizontal bar."""
    d, w, h, t, dt, wt = depth, width, height, 0.015, 0.018, 0.008
    bay = (h - 2 * t - (n - 1) * t) / n
    body = shell(d, w, h, t, WOOD)
    links, joints = [], []
    for i in range(n):
        top = h - t - i * (bay + t)
        bot = top - bay
        if i < n - 1:
            body.append(box((-d / 2, -w / 2 + t, bot - t), (d / 2 - t, w / 2 - t, bot), WOOD))
        bd, bw, bh = d - t - 0.03, w / 2 - t - 0.004, bay - 0.02  # bin depth, half width, wall height
        shapes = [
            box((-dt, -w / 2 + 0.003, -t / 2 + 0.002), (0.0, w / 2 - 0.003, bay + t / 2 - 0.002), WOOD),  # front
            box((0.0, -bw, 0.003), (bd, bw, 0.003 + wt), WOOD),  # bottom
            box((0.0, -bw, 0.003), (bd, -bw + wt, bh), WOOD),
            box((0.0, bw - wt, 0.003), (bd, bw, bh), WOOD),
            box((bd - wt, -bw, 0.003), (bd, bw, bh), WOOD),
        ]
        handle, grip = bar_handle(-dt, 0.0, bay / 2, 0.14, "y")
        links.append(Link(f"drawer_{i}", 1.2, tuple(shapes + handle)))
        joints.append(Joint(f"drawer_{i}_slide", "prismatic", "body", f"drawer_{i}", (-d / 2, 0.0, bot),
                            (-1.0, 0.0, 0.0),
                            (0.0, 0.3), 0.0, 0.2, grip, damping=1.0, friction=0.05,
                            holds=((wt, -bw + wt, 0.003 + wt), (bd - wt, bw - wt, bh))))
    return Model(id, "drawer_chest", ("furniture", "container", "drawer"),
                 (Link("body", 9.0, tuple(body)), *links), tuple(joints),
                 params={"depth": d, "width": w, "height": h, "drawers": float(n)})


def microwave(id: str, depth: float, width: float, height: float, panel: float) -> Model:
    """Microwave: white shell, control panel on the right, glass door hinged on the left, bar on its right edge."""
    d, w, h, t, dt = depth, width, height, 0.012, 0.02
    body = shell(d, w, h, t, WHITE) + [
        box((-d / 2 - dt, -w / 2, 0.0), (-d / 2 + 0.04, -w / 2 + panel, h), DARK),  # control panel, flush with door
    ]
    origin, axis, door, grip = side_door(d, w, -w / 2 + panel + 0.002, w / 2, 0.002, h - 0.002, "left", dt, DARK,
                                         round(0.55 * h, 3), h / 2)
    return Model(id, "microwave", ("appliance", "kitchen", "container", "door"),
                 (Link("body", 11.0, tuple(body)), Link("door", 1.2, tuple(door))),
                 (Joint("door_hinge", "revolute", "body", "door", origin, axis, (0.0, 1.9), 0.0, 1.4, grip),),
                 params={"depth": d, "width": w, "height": h, "panel_width": panel, "hinge": "left"})


def oven(id: str, depth: float, width: float, height: float) -> Model:
    """Countertop oven: 7 cm base, control strip on top, bottom-hinged door with a horizontal bar."""
    d, w, h, t, dt, base, strip = depth, width, height, 0.012, 0.02, 0.07, 0.07
    body = shell(d, w, h, t, STEEL, z0=base) + [
        box((-d / 2, -w / 2, 0.0), (d / 2, w / 2, base), DARK),
        box((-d / 2 - dt, -w / 2, h - strip), (-d / 2 + 0.03, w / 2, h), DARK),
    ]
    origin, door, grip = bottom_door(d, w / 2 - 0.004, base + 0.002, h - strip - 0.002, dt, DARK,
                                     0.20 if w >= 0.48 else 0.18)
    return Model(id, "oven", ("appliance", "kitchen", "container", "door"),
                 (Link("body", 14.0, tuple(body)), Link("door", 2.5, tuple(door))),
                 (Joint("door_hinge", "revolute", "body", "door", origin, (0.0, -1.0, 0.0), (0.0, 1.57), 0.0, 1.3,
                        grip, damping=0.5),),
                 params={"depth": d, "width": w, "height": h, "hinge": "bottom"})


def dishwasher(id: str, rack: bool, depth: float = 0.46, width: float = 0.45, height: float = 0.44) -> Model:
    """Countertop dishwasher: bottom-hinged full-height door with a bar on top; optionally a sliding rack."""
    d, w, h, t, dt, base = depth, width, height, 0.012, 0.022, 0.06
    body = shell(d, w, h, t, WHITE, z0=base) + [box((-d / 2, -w / 2, 0.0), (d / 2, w / 2, base), DARK)]
    origin, door, grip = bottom_door(d, w / 2 - 0.004, base + 0.002, h - 0.002, dt, WHITE, 0.18)
    links = [Link("body", 16.0, tuple(body)), Link("door", 3.0, tuple(door))]
    joints = [Joint("door_hinge", "revolute", "body", "door", origin, (0.0, -1.0, 0.0), (0.0, 1.57), 0.0, 1.45, grip,
                    damping=0.5)]
    if rack:
        rd, rw, rt, rim = d - t - 0.05, w / 2 - t - 0.01, 0.006, 0.05
        shapes = [box((0.0, -rw, 0.0), (rd, rw, rt), STEEL),
                  box((0.0, -rw, 0.0), (rd, -rw + rt, rim), STEEL), box((0.0, rw - rt, 0.0), (rd, rw, rim), STEEL),
                  box((rd - rt, -rw, 0.0), (rd, rw, rim), STEEL), box((0.0, -rw, 0.0), (rt, rw, rim), STEEL),
                  cyl((-0.009, 0.0, rim), 0.009, 2 * rw, "y", STEEL)]  # front rail = handle, Ø 1.8 cm
        links.append(Link("rack", 0.8, tuple(shapes)))
        joints.append(Joint("rack_slide", "prismatic", "body", "rack", (-d / 2 + 0.02, 0.0, base + 0.09),
                            (-1.0, 0.0, 0.0), (0.0, 0.32), 0.0, 0.25, (-0.009, 0.0, rim), damping=1.0, friction=0.05))
    return Model(id, "dishwasher", ("appliance", "kitchen", "container", "door") + (("drawer",) if rack else ()),
                 tuple(links), tuple(joints),
                 params={"depth": d, "width": w, "height": h, "rack": "yes" if rack else "no"})


def refrigerator(id: str, hinge: Literal["left", "right"], depth: float, width: float, height: float) -> Model:
    """Compact fridge: 3 cm feet, two inner shelves, thick full-height door with a 20 cm vertical bar at 0.52 m."""
    d, w, h, t, dt, base = depth, width, height, 0.02, 0.04, 0.03
    body = shell(d, w, h, t, WHITE, z0=base) + [box((-d / 2, -w / 2, 0.0), (d / 2, w / 2, base), DARK)]
    for z in (0.35 * h, 0.65 * h):
        body.append(box((-d / 2 + 0.02, -w / 2 + t, z - 0.004), (d / 2 - t, w / 2 - t, z + 0.004), SILVER))
    origin, axis, door, grip = side_door(d, w, -w / 2, w / 2, base + 0.002, h - 0.002, hinge, dt, WHITE, 0.20, 0.52,
                                         bar_r=0.012)
    return Model(id, "refrigerator", ("appliance", "kitchen", "container", "door"),
                 (Link("body", 25.0, tuple(body)), Link("door", 4.0, tuple(door))),
                 (Joint("door_hinge", "revolute", "body", "door", origin, axis, (0.0, 1.9), 0.0, 1.4, grip,
                        damping=0.5),),
                 params={"depth": d, "width": w, "height": h, "hinge": hinge})


def laptop(id: str, depth: float, width: float, base_h: float, lid_t: float = 0.007) -> Model:
    """Free laptop: base slab, lid hinged on the base's back top edge; the lid overhangs the front by 6 mm and
    its front edge centre is the grip point."""
    d, w = depth, width
    body = [box((-d / 2, -w / 2, 0.0), (d / 2, w / 2, base_h), SILVER)]
    lip = 0.006
    lid = [box((-d - lip, -w / 2, 0.0), (0.0, w / 2, lid_t), SILVER)]
    return Model(id, "laptop", ("electronics", "lid"),
                 (Link("body", 1.2, tuple(body)), Link("lid", 0.5, tuple(lid))),
                 (Joint("lid_hinge", "revolute", "body", "lid", (d / 2, 0.0, base_h), (0.0, 1.0, 0.0), (0.0, 2.2), 0.0,
                        1.75, (-d - lip, 0.0, lid_t / 2), damping=0.1, friction=0.05, effort=10.0),),
                 fixed_base=False, params={"depth": d, "width": w, "base_height": base_h, "lid_thickness": lid_t})


def box_with_lid(id: str, depth: float, width: float, height: float, wall: float, masses: tuple[float, float]) -> Model:
    """Free open-top box with a lid hinged on its back top edge and a small tab on the lid's front edge."""
    d, w, h, lt = depth, width, height, 0.008
    body = shell(d, w, h - lt, wall, PLASTIC, open_faces=("+z",))
    lid_shapes, grip = tab(-d, 0.0, 0.006)
    lid = [box((-d, -w / 2, 0.0), (0.0, w / 2, lt), PLASTIC)] + lid_shapes
    return Model(id, "box_with_lid", ("container", "box", "lid"),
                 (Link("body", masses[0], tuple(body)), Link("lid", masses[1], tuple(lid))),
                 (Joint("lid_hinge", "revolute", "body", "lid", (d / 2, 0.0, h - lt), (0.0, 1.0, 0.0), (0.0, 2.0), 0.0,
                        1.6, grip, damping=0.05, friction=0.01, effort=10.0),),
                 fixed_base=False, friction=0.6, params={"depth": d, "width": w, "height": h, "wall": wall})


def trash_can(id: str, depth: float, width: float, height: float) -> Model:
    """Rectangular bin (open top) with a lid hinged at the back and a tab on its front edge."""
    d, w, h, lt = depth, width, height, 0.015
    body = shell(d, w, h - lt, 0.008, STEEL, open_faces=("+z",))
    lid_shapes, grip = tab(-d - 0.004, 0.0, 0.01, out=0.03, width=0.06)
    lid = [box((-d - 0.004, -w / 2 - 0.004, 0.0), (0.0, w / 2 + 0.004, lt), DARK)] + lid_shapes
    return Model(id, "trash_can", ("container", "furniture", "lid"),
                 (Link("body", 2.5, tuple(body)), Link("lid", 0.4, tuple(lid))),
                 (Joint("lid_hinge", "revolute", "body", "lid", (d / 2, 0.0, h - lt), (0.0, 1.0, 0.0), (0.0, 1.9), 0.0,
                        1.4, grip, damping=0.1, friction=0.02, effort=20.0),),
                 params={"depth": d, "width": w, "height": h})


def faucet(id: str, mode: Literal["swivel", "lift"]) -> Model:
    """Single-lever tap: base disc, 17 cm column, spout towards -x; the lever points -x from the column top.

    ``swivel``: lever turns about the vertical column axis (quarter turn, towards -y). ``lift``: lever tilts up
    about a horizontal y axis."""
    top = 0.17
    body = [cyl((0.0, 0.0, 0.006), 0.035, 0.012, "z", STEEL), cyl((0.0, 0.0, top / 2), 0.022, top, "z", STEEL),
            cyl((-0.08, 0.0, 0.13), 0.012, 0.16, "x", STEEL), cyl((-0.15, 0.0, 0.115), 0.012, 0.03, "z", STEEL)]
    lever_bar = lambda z: box((-0.11, -0.0125, z), (-0.005, 0.0125, z + 0.015), STEEL)  # noqa: E731
    if mode == "swivel":
        lever = [cyl((0.0, 0.0, 0.0125), 0.018, 0.025, "z", STEEL), lever_bar(0.016)]
        grip = (-0.075, 0.0, 0.0235)
        joint = Joint("lever_hinge", "revolute", "body", "lever", (0.0, 0.0, top), (0.0, 0.0, 1.0), (0.0, 1.57), 0.0,
                      1.2, grip, damping=0.02, friction=0.005, effort=5.0)
    else:
        body.append(cyl((0.0, 0.0, top + 0.01), 0.02, 0.02, "z", STEEL))  # fixed cap under the lever
        lever = [cyl((0.0, 0.0, 0.0), 0.01, 0.03, "y", STEEL), lever_bar(-0.0075)]
        grip = (-0.075, 0.0, 0.0)
        joint = Joint("lever_hinge", "revolute", "body", "lever", (0.0, 0.0, top + 0.03), (0.0, 1.0, 0.0), (0.0, 0.6),
                      0.0, 0.45, grip, damping=0.02, friction=0.005, effort=5.0)
    return Model(id, "faucet", ("fixture", "kitchen", "lever"),
                 (Link("body", 1.0, tuple(body)), Link("lever", 0.15, tuple(lever))), (joint,), friction=0.7,
                 params={"mode": mode, "column_height": top})


def valve(id: str, top: float = 0.12, lever: float = 0.13) -> Model:
    """A quarter-turn ball valve on an upright pipe ``top`` m tall, its lever (``lever`` m) pointing -x: the lever
    turns 90° about the pipe's vertical axis (towards -y)."""
    body = [cyl((0.0, 0.0, 0.006), 0.04, 0.012, "z", STEEL), cyl((0.0, 0.0, top / 2), 0.018, top, "z", STEEL),
            cyl((0.0, 0.0, top - 0.045), 0.026, 0.07, "y", SILVER)]  # base flange, riser, valve body across it
    arm = [cyl((0.0, 0.0, 0.01), 0.015, 0.02, "z", STEEL), box((-lever, -0.012, 0.012), (-0.005, 0.012, 0.027), RED)]
    grip = (-0.7 * lever, 0.0, 0.0195)
    joint = Joint("lever_hinge", "revolute", "body", "lever", (0.0, 0.0, top), (0.0, 0.0, 1.0), (0.0, 1.57), 0.0, 1.2,
                  grip, damping=0.02, friction=0.005, effort=5.0)
    return Model(id, "valve", ("fixture", "plumbing", "lever"),
                 (Link("body", 1.2, tuple(body)), Link("lever", 0.12, tuple(arm))), (joint,), friction=0.7,
                 params={"pipe_height": top, "lever_length": lever})


def knob(id: str, style: Literal["stove", "dial"]) -> Model:
    """A control knob on a small upright panel, turning about x (counter-clockwise seen from the front opens)."""
    if style == "stove":
        panel, zc = (0.06, 0.24, 0.16), 0.09
        shapes = [cyl((-0.006, 0.0, 0.0), 0.021, 0.012, "x", DARK), cyl((-0.021, 0.0, 0.0), 0.016, 0.02, "x", DARK),
                  box((-0.034, -0.004, -0.019), (-0.012, 0.004, 0.019), DARK)]  # skirt, body, grip fin
        grip, limits, opened, mass = (-0.024, 0.0, 0.0), (0.0, 4.71), 1.57, 0.04
    else:
        panel, zc = (0.08, 0.20, 0.20), 0.11
        shapes = [cyl((-0.015, 0.0, 0.0), 0.03, 0.03, "x", DARK),
                  box((-0.034, -0.003, 0.006), (-0.028, 0.003, 0.026), WHITE)]  # dial, pointer ridge
        grip, limits, opened, mass = (-0.015, 0.0, 0.0), (0.0, 5.24), 2.6, 0.08
    px, py, pz = panel
    body = [box((-px / 2, -py / 2, 0.0), (px / 2, py / 2, pz), WHITE)]
    com = (grip[0], 0.0, 0.0)  # on the axis, so gravity never turns the knob
    return Model(id, "knob", ("appliance", "control", "knob"),
                 (Link("body", 1.5, tuple(body)), Link("knob", mass, tuple(shapes), com)),
                 (Joint("knob_joint", "revolute", "body", "knob", (-px / 2, 0.0, zc), (-1.0, 0.0, 0.0), limits, 0.0,
                        opened, grip, damping=0.002, friction=0.0005, effort=2.0),),
                 friction=0.9, params={"style": style, "knob_height": zc})


def push_button(id: str, style: Literal["estop", "arcade"]) -> Model:
    """A push button on a housing that stands on the table; its cap slides straight down when pressed.

    ``estop``: a red mushroom cap (Ø 5 cm) on a yellow box; pushed past half its 12 mm travel it latches down (detents
    at both ends). ``arcade``: a green cap (Ø 4 cm) on a round housing; it springs back up when let go (one detent,
    up)."""
    if style == "estop":
        housing, top = [box((-0.05, -0.05, 0.0), (0.05, 0.05, 0.07), YELLOW)], 0.07
        cap = [cyl((0.0, 0.0, 0.01), 0.012, 0.02, "z", DARK), cyl((0.0, 0.0, 0.028), 0.025, 0.016, "z", RED)]
        travel, detents, spring, cap_top = 0.012, (0.0, 1.0), 800.0, 0.036
    else:
        housing, top = [cyl((0.0, 0.0, 0.025), 0.05, 0.05, "z", DARK)], 0.05
        cap = [cyl((0.0, 0.0, 0.011), 0.02, 0.022, "z", GREEN)]
        travel, detents, spring, cap_top = 0.01, (0.0,), 600.0, 0.022
    joint = Joint("button_slide", "prismatic", "body", "button", (0.0, 0.0, top), (0.0, 0.0, -1.0), (0.0, travel), 0.0,
                  travel, (0.0, 0.0, cap_top), damping=3.0, friction=0.0, effort=50.0, velocity=0.5,
                  detents=detents, spring=spring)
    return Model(id, "button", ("control", "button", "press"),
                 (Link("body", 1.5, tuple(housing)), Link("button", 0.02, tuple(cap))), (joint,), friction=0.9,
                 params={"style": style, "travel": travel, "housing_height": top,
                         "color": "red" if style == "estop" else "green"})


def lever_switch(id: str, length: float = 0.1, pivot: float = 0.1) -> Model:
    """A lever switch on the front of a grey box: the lever (``length`` m) sticks out towards -x from a pivot
    ``pivot`` m up and swings about y, tip up for off, tip down for on (0.35 rad each way of level). It snaps to
    whichever side it was pushed past level (detents at both ends)."""
    d, w, h = 0.08, 0.1, pivot + 0.05
    base = [box((-d / 2, -w / 2, 0.0), (d / 2, w / 2, h), SILVER)]
    lever = [cyl((0.0, 0.0, 0.0), 0.01, 0.03, "y", DARK), box((-length, -0.011, -0.006), (0.0, 0.011, 0.006), DARK),
             box((-length, -0.016, -0.009), (-length + 0.025, 0.016, 0.009), RED)]
    joint = Joint("lever_hinge", "revolute", "body", "lever", (-d / 2 - 0.01, 0.0, pivot), (0.0, -1.0, 0.0),
                  (-0.35, 0.35), -0.35, 0.35, (-length + 0.0125, 0.0, 0.009), damping=0.01, friction=0.0, effort=5.0,
                  velocity=3.0, detents=(0.0, 1.0), spring=1.5)
    return Model(id, "switch", ("control", "switch", "press"),
                 (Link("body", 1.2, tuple(base)), Link("lever", 0.05, tuple(lever), (0.0, 0.0, 0.0))), (joint,),
                 friction=0.9, params={"lever_length": length, "pivot_height": pivot, "color": "grey"})


SCREW_RIM_FRICTION_N = 2.0
"""The thread's dry friction at the cap's rim (N; times the cap's radius: the torque a grip must overcome)."""
SCREW_STYLES: dict[str, tuple[float, float, float, float, float, RGBA, str]] = {
    # style: body radius, body height, neck radius (0: none), cap radius, cap height, cap colour, its name
    "jar": (0.042, 0.10, 0.0, 0.045, 0.024, RED, "red"),
    "jar_small": (0.036, 0.085, 0.0, 0.039, 0.02, YELLOW, "yellow"),
    "bottle": (0.04, 0.15, 0.028, 0.031, 0.025, WHITE, "white"),
    "bottle_tall": (0.038, 0.20, 0.027, 0.03, 0.025, RED, "red"),
    "canister": (0.05, 0.13, 0.0, 0.053, 0.03, DARK, "black"),
    "canister_small": (0.045, 0.10, 0.0, 0.048, 0.028, WHITE, "white"),
}
"""The screw-top containers (:func:`screw_cap`): a glass jar and a jam jar, a wide-mouth bottle and a tall one, a
steel kitchen canister and a small one."""


def screw_cap(id: str, style: str) -> Model:
    """A container fixed to the table under a cap that screws about the vertical axis (:data:`SCREW_STYLES`):
    counter-clockwise (seen from above) unscrews it, one full turn frees it (the joint's open end); thread friction
    holds it wherever the hand leaves it. A bottle has a 1.5 cm neck under its cap; its category is ``bottle``."""
    r_body, h_body, r_neck, r, h, rgba, color = SCREW_STYLES[style]
    glass, green = (0.80, 0.88, 0.90, 1.0), GREEN
    kind = style.split("_")[0]
    body_rgba = {"jar": glass, "bottle": green, "canister": STEEL}[kind]
    body = [cyl((0.0, 0.0, h_body / 2), r_body, h_body, "z", body_rgba)]
    top = h_body
    if r_neck:
        body.append(cyl((0.0, 0.0, h_body + 0.0075), r_neck, 0.015, "z", body_rgba))
        top = h_body + 0.015
    joint = Joint("cap_screw", "revolute", "body", "cap", (0.0, 0.0, top), (0.0, 0.0, 1.0), (0.0, 2 * math.pi), 0.0,
                  2 * math.pi, (0.0, 0.0, h), damping=0.05, friction=0.02, effort=2.0, velocity=4.0,
                  friction_limit=round(SCREW_RIM_FRICTION_N * r, 4))
    return Model(id, kind, ("container", "kitchen", "screw"),
                 (Link("body", 0.8, tuple(body)), Link("cap", 0.05, (cyl((0.0, 0.0, h / 2), r, h, "z", rgba),))),
                 (joint,), friction=1.0,
                 params={"style": style, "cap_radius": r, "cap_height": h, "cap_top": top + h, "color": color})


VARIANTS: dict[str, Callable[[], Model]] = {
    "cabinet_left_hinge": lambda: cabinet("cabinet_left_hinge", "left"),
    "cabinet_right_hinge": lambda: cabinet("cabinet_right_hinge", "right", 0.36, 0.38, 0.56, "knob_bar"),
    "drawer_chest_1": lambda: drawer_chest("drawer_chest_1", 1, 0.38, 0.42, 0.24),
    "drawer_chest_2": lambda: drawer_chest("drawer_chest_2", 2, 0.40, 0.45, 0.40),
    "drawer_chest_3": lambda: drawer_chest("drawer_chest_3", 3, 0.40, 0.45, 0.52),
    "microwave_standard": lambda: microwave("microwave_standard", 0.36, 0.48, 0.29, 0.11),
    "microwave_compact": lambda: microwave("microwave_compact", 0.32, 0.42, 0.25, 0.095),
    "oven_standard": lambda: oven("oven_standard", 0.45, 0.50, 0.45),
    "oven_compact": lambda: oven("oven_compact", 0.38, 0.44, 0.38),
    "dishwasher_plain": lambda: dishwasher("dishwasher_plain", False),
    "dishwasher_rack": lambda: dishwasher("dishwasher_rack", True),
    "refrigerator_left_hinge": lambda: refrigerator("refrigerator_left_hinge", "left", 0.50, 0.48, 0.85),
    "refrigerator_right_hinge": lambda: refrigerator("refrigerator_right_hinge", "right", 0.48, 0.46, 0.80),
    "laptop_13in": lambda: laptop("laptop_13in", 0.21, 0.30, 0.016),
    "laptop_15in": lambda: laptop("laptop_15in", 0.245, 0.355, 0.02),
    "box_with_lid_small": lambda: box_with_lid("box_with_lid_small", 0.16, 0.22, 0.10, 0.006, (0.25, 0.08)),
    "box_with_lid_large": lambda: box_with_lid("box_with_lid_large", 0.26, 0.36, 0.16, 0.01, (0.9, 0.3)),
    "trash_can_small": lambda: trash_can("trash_can_small", 0.20, 0.24, 0.30),
    "trash_can_tall": lambda: trash_can("trash_can_tall", 0.26, 0.30, 0.40),
    "faucet_lever_swivel": lambda: faucet("faucet_lever_swivel", "swivel"),
    "faucet_lever_lift": lambda: faucet("faucet_lever_lift", "lift"),
    "valve_lever": lambda: valve("valve_lever"),
    "valve_lever_short": lambda: valve("valve_lever_short", 0.09, 0.10),
    "knob_stove": lambda: knob("knob_stove", "stove"),
    "knob_dial": lambda: knob("knob_dial", "dial"),
    **{f"screw_{style}": (lambda style=style: screw_cap(f"screw_{style}", style)) for style in SCREW_STYLES},
    "button_estop": lambda: push_button("button_estop", "estop"),
    "button_arcade": lambda: push_button("button_arcade", "arcade"),
    "switch_lever": lambda: lever_switch("switch_lever"),
    "switch_lever_tall": lambda: lever_switch("switch_lever_tall", 0.12, 0.15),
}
"""Every shipped variant, by asset id."""
