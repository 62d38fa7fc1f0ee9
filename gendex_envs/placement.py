"""Collision-free random layouts at reset: every object's pose noise drawn so that no two footprints overlap.

Each object has a :class:`Footprint` — the rectangle it covers on the table at the spec's orientation, from its
catalog bounding box; its yaw noise turns it about the object's origin. :func:`place` draws the objects' noise in
spec order, batched over envs: an env whose drawn object would overlap one placed before it (with :data:`GAP_M`
between them) or leave the table (unless it is fixed) draws again, up to :data:`TRIES` times; an env where an object
never finds room draws its whole layout again (:data:`ROUNDS`), and one that never succeeds keeps the nominal layout.
An object that starts in a container (:attr:`Item.starts_in`) moves with it.
The draws come from torch's RNG, which ManiSkill seeds from the reset seed, so a layout is a function of the seed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch

GAP_M = 0.01
"""Least gap between two objects' footprints after randomization."""
TRIES = 32
"""Draws per object and env before the env's layout is drawn again."""
ROUNDS = 8
"""Whole-layout draws per env before it falls back to the nominal layout."""
STARTS_IN_MIN_CLEARANCE_M = 0.005
"""An object raised more than this off the table, over a container, starts in it (and moves with it at reset)."""


@dataclass(frozen=True)
class Footprint:
    """A rectangle on the table in an object's frame: centre offset from the origin (x, y) and half extents."""

    offset: tuple[float, float]
    half: tuple[float, float]


def _axes(yaw: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    c, s = torch.cos(yaw), torch.sin(yaw)
    return torch.stack([c, s], -1), torch.stack([-s, c], -1)


def corners_center(pos: torch.Tensor, yaw: torch.Tensor, fp: Footprint) -> torch.Tensor:
    """[B, 2] world centre of the footprint of an object at ``pos`` [B, 2] turned by ``yaw`` [B]."""
    u, v = _axes(yaw)
    return pos + u * fp.offset[0] + v * fp.offset[1]


def overlap(ca: torch.Tensor, yaw_a: torch.Tensor, fa: Footprint, cb: torch.Tensor, yaw_b: torch.Tensor,
            fb: Footprint, gap: float = GAP_M) -> torch.Tensor:
    """[B] bool: rectangles a and b (footprint centres [B, 2], yaws [B]) come closer than ``gap`` (separating axes)."""
    ua, va = _axes(yaw_a)
    ub, vb = _axes(yaw_b)
    d = cb - ca
    hit = torch.ones(len(d), dtype=torch.bool, device=d.device)
    for n in (ua, va, ub, vb):
        ra = fa.half[0] * (ua * n).sum(-1).abs() + fa.half[1] * (va * n).sum(-1).abs()
        rb = fb.half[0] * (ub * n).sum(-1).abs() + fb.half[1] * (vb * n).sum(-1).abs()
        hit &= (d * n).sum(-1).abs() < ra + rb + gap
    return hit


def on_table(center: torch.Tensor, yaw: torch.Tensor, fp: Footprint, table_half: tuple[float, float]) -> torch.Tensor:
    """[B] bool: the footprint lies on the table top (centred at the origin, half extents ``table_half``)."""
    u, v = _axes(yaw)
    ext_x = fp.half[0] * u[:, 0].abs() + fp.half[1] * v[:, 0].abs()
    ext_y = fp.half[0] * u[:, 1].abs() + fp.half[1] * v[:, 1].abs()
    return (center[:, 0].abs() + ext_x <= table_half[0]) & (center[:, 1].abs() + ext_y <= table_half[1])


@dataclass(frozen=True)
class Item:
    """One object to place: nominal position (x, y), noise half-ranges, footprint at the nominal orientation."""

    name: str
    pos: tuple[float, float]
    noise_xy: tuple[float, float]
    noise_yaw_rad: float
    footprint: Footprint
    fixed: bool = False
    """Fixed objects (a cabinet against the table's back edge) may overhang the table; others must lie on it."""
    starts_in: str | None = None
    """The container this object starts in (*take the apple out of the bowl*): it moves with the container's xy
    noise (drawn first), turns by its own yaw noise, and is not kept apart from anything (it is inside)."""


def starts_in(obj, objects, records) -> str | None:
    """The container spec object ``obj`` starts in: a rigid container (catalog tag ``container``) whose footprint
    holds ``obj``'s origin, or a chest whose slid-out drawer's bin does (:func:`in_drawer`), for a rigid object
    raised more than :data:`STARTS_IN_MIN_CLEARANCE_M` off the table (what the physical checks call
    ``inside_container``); None otherwise. ``records``: each object's catalog record."""
    if obj.pos_m[2] <= STARTS_IN_MIN_CLEARANCE_M or records[obj.name].articulated:
        return None
    for other in objects:
        rec = records[other.name]
        if other.name != obj.name and rec.articulated and in_drawer(obj, other, rec):
            return other.name
        if other.name == obj.name or "container" not in rec.tags or rec.articulated:
            continue
        half = [v * other.scale / 2 for v in rec.size_m[:2]]
        if all(abs(obj.pos_m[k] - other.pos_m[k]) < half[k] for k in (0, 1)):
            return other.name
    return None


def in_drawer(obj, chest, rec) -> bool:
    """Object ``obj``'s nominal origin lies in the bin of a drawer of articulated ``chest`` (catalog record ``rec``)
    slid out as far as the chest's ``joint_state`` says (a drawer slides its link along -x of the asset frame)."""
    w, z = chest.quat_wxyz[0], chest.quat_wxyz[3]
    yaw = 2.0 * math.atan2(z, w)
    dx, dy = obj.pos_m[0] - chest.pos_m[0], obj.pos_m[1] - chest.pos_m[1]
    x = (math.cos(yaw) * dx + math.sin(yaw) * dy) / chest.scale  # in the chest's frame, at scale 1
    y = (-math.sin(yaw) * dx + math.cos(yaw) * dy) / chest.scale
    for j in rec.joints:
        if j.holds_m is None or j.link_origin_m is None:
            continue
        q = chest.joint_state.get(j.name, j.closed_qpos)
        lx, ly = x - j.link_origin_m[0] + q, y - j.link_origin_m[1]
        (x0, y0, _), (x1, y1, _) = j.holds_m
        if x0 <= lx <= x1 and y0 <= ly <= y1:
            return True
    return False


def place(items: list[Item], batch: int, table_half: tuple[float, float], device=None
          ) -> dict[str, tuple[torch.Tensor, torch.Tensor]]:
    """Noise for every item: name -> (xy offset [B, 2], yaw offset [B]), layouts free of overlaps (module doc).

    An env where some object found no room is drawn again as a whole, up to :data:`ROUNDS` times; one that never
    succeeds keeps every object's nominal pose (the spec's layout, which the physical checks keep free)."""
    out, ok = _draw(items, batch, table_half, device)
    for _ in range(ROUNDS - 1):
        if bool(ok.all()):
            break
        again, ok_again = _draw(items, batch, table_half, device)
        take = ~ok & ok_again
        for name, (dxy, dyaw) in again.items():
            out[name][0][take] = dxy[take]
            out[name][1][take] = dyaw[take]
        ok |= ok_again
    for dxy, dyaw in out.values():
        dxy[~ok] = 0.0
        dyaw[~ok] = 0.0
    return out


def _draw(items: list[Item], batch: int, table_half: tuple[float, float], device=None
          ) -> tuple[dict[str, tuple[torch.Tensor, torch.Tensor]], torch.Tensor]:
    """One layout per env, objects drawn in order (module doc); and [B] bool: every object found room."""
    placed: list[tuple[Item, torch.Tensor, torch.Tensor]] = []  # item, footprint centre [B, 2], yaw [B]
    out: dict[str, tuple[torch.Tensor, torch.Tensor]] = {}
    all_ok = torch.ones(batch, dtype=torch.bool, device=device)
    by_name = {it.name: it for it in items}
    for it in sorted(items, key=lambda it: it.starts_in is not None):  # containers before what starts in them
        base = torch.tensor(it.pos, dtype=torch.float32, device=device).expand(batch, 2)
        noise_xy = torch.zeros(batch, 2, device=device)
        noise_yaw = torch.zeros(batch, device=device)
        if it.starts_in is not None:
            if it.noise_yaw_rad > 0:
                noise_yaw = (torch.rand(batch, device=device) * 2 - 1) * it.noise_yaw_rad
            # it moves with its container, and turns with it about the container's origin (a drawer's bin lies
            # 30 cm out of its chest's)
            dxy, dyaw = out[it.starts_in]
            rel = base - torch.tensor(by_name[it.starts_in].pos, dtype=torch.float32, device=device)
            c, s = torch.cos(dyaw), torch.sin(dyaw)
            turned = torch.stack([c * rel[:, 0] - s * rel[:, 1], s * rel[:, 0] + c * rel[:, 1]], dim=-1)
            out[it.name] = (dxy + turned - rel, noise_yaw)
            continue
        todo = torch.ones(batch, dtype=torch.bool, device=device)
        moves = it.noise_xy[0] > 0 or it.noise_xy[1] > 0
        turns = it.noise_yaw_rad > 0
        if not (moves or turns):
            todo[:] = False
        for _ in range(TRIES if moves or turns else 0):
            if not bool(todo.any()):
                break
            # draw only what the object randomizes: a layout without overlaps keeps the draws of one try each
            dxy = ((torch.rand(batch, 2, device=device) * 2 - 1) * torch.tensor(it.noise_xy, device=device)
                   if moves else torch.zeros(batch, 2, device=device))
            dyaw = ((torch.rand(batch, device=device) * 2 - 1) * it.noise_yaw_rad if turns
                    else torch.zeros(batch, device=device))
            center = corners_center(base + dxy, dyaw, it.footprint)
            ok = (torch.ones(batch, dtype=torch.bool, device=device) if it.fixed
                  else on_table(center, dyaw, it.footprint, table_half))
            for other, oc, oyaw in placed:
                ok &= ~overlap(center, dyaw, it.footprint, oc, oyaw, other.footprint)
            take = todo & ok
            noise_xy[take] = dxy[take]
            noise_yaw[take] = dyaw[take]
            todo &= ~ok
        all_ok &= ~todo
        placed.append((it, corners_center(base + noise_xy, noise_yaw, it.footprint), noise_yaw))
        out[it.name] = (noise_xy, noise_yaw)
    return out, all_ok
