"""The ``poured`` condition's pieces: the loose things (catalog tag ``pourable``: beads, marbles) that start in a
vessel, and the share of them that now lie in a container.

A piece *starts in* a vessel as any object starts in a container (:func:`gendex_envs.placement.starts_in`: raised off
the table over its footprint); the spec lists each piece as its own object, so every piece is a rigid body the
simulator moves, and a pour is counted only where the pieces really fell into the target. A piece counts as in the
target by the ``inside`` condition's own test (:func:`gendex_envs.success.in_container`), so "poured" and "inside"
never disagree about one bead.
"""

from __future__ import annotations

import dataclasses
import math
import weakref
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import torch

from gendex_envs.errors import TaskSpecError
from gendex_envs.placement import starts_in

if TYPE_CHECKING:  # pragma: no cover
    from gendex_envs.spec import TaskSpec
    from gendex_envs.task_env import TaskEnv

POURABLE_TAG = "pourable"
"""Catalog tag of a loose piece a vessel pours (:mod:`gendex_envs.assets.procedural_pouring`)."""

RING_FRACTION = 0.4
"""Pieces are laid on a ring this fraction of the vessel's half width from its axis (its foot is narrower than its
mouth)."""
PIECE_GAP_M = 0.0015
"""Gap between neighbouring pieces of a layer, and between layers, as laid (they settle at the first steps)."""
MAX_PIECES = 24
"""At most this many pieces fill one vessel (each is an object of the task, and a task holds at most 64)."""

_PIECES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def fill_layout(vessel, piece, count: int, vessel_scale: float = 1.0) -> list[tuple[float, float, float]]:
    """Where ``count`` pieces (catalog record ``piece``) are laid in vessel ``vessel`` (its catalog record) at
    ``vessel_scale``: (dx, dy, clearance) per piece, dx and dy from the vessel's origin in its frame, clearance the
    height of the piece's lowest point over the table (as a spec's ``pos_m`` z), in layers on a ring
    (:data:`RING_FRACTION`) from the vessel's floor up, each layer turned half a place from the one below.
    ValueError if they do not fit below its rim."""
    d = float(piece.bbox_max_m[2] - piece.bbox_min_m[2])
    half = vessel_scale * min(vessel.bbox_max_m[0], vessel.bbox_max_m[1])
    ring = RING_FRACTION * half
    chord = (d + PIECE_GAP_M) / (2 * ring)
    per_layer = 1 if chord >= 1 else max(1, int(math.pi / math.asin(chord)))
    floor = vessel_scale * float(vessel.entry.params.get("cavity_z", 0.0)) + PIECE_GAP_M
    top = vessel_scale * float(vessel.entry.params.get("rim_z", vessel.bbox_max_m[2]))
    out = []
    for k in range(count):
        layer, place = divmod(k, per_layer)
        z = floor + layer * (d + PIECE_GAP_M)
        if z + d > top:
            raise ValueError(f"{count} pieces of {d * 1000:.0f} mm do not fit in a vessel {top * 100:.1f} cm deep "
                             f"({per_layer} a layer)")
        a = 2 * math.pi * (place + 0.5 * (layer % 2)) / per_layer
        r = ring if per_layer > 1 else 0.0
        out.append((round(r * math.cos(a), 4), round(r * math.sin(a), 4), round(z, 4)))
    return out


def spec_pieces(spec, records, vessel: str) -> tuple[str, ...]:
    """Names of the spec objects tagged ``pourable`` that start in ``vessel`` (``records``: each object's catalog
    record by name), in spec order."""
    return tuple(o.name for o in spec.objects
                 if POURABLE_TAG in records[o.name].tags and starts_in(o, spec.objects, records) == vessel)


def pieces(env: TaskEnv, vessel: str) -> tuple[str, ...]:
    """The pieces that start in object ``vessel`` of ``env``'s task; TaskSpecError if there are none (a ``poured``
    condition about a vessel that holds nothing could never hold, or would hold for nothing)."""
    cache = _PIECES.setdefault(env, {})
    if vessel not in cache:
        spec = env.task_spec
        records = {o.name: env.asset_record(o.name) for o in spec.objects}
        found = spec_pieces(spec, records, vessel)
        if not found:
            raise TaskSpecError(f"object {vessel!r} holds no pieces to pour: a 'poured' condition's object is a vessel "
                                f"that objects tagged {POURABLE_TAG!r} (e.g. bead, marble) start in (raised off the "
                                "table over its footprint)")
        cache[vessel] = found
    return cache[vessel]


def share(env: TaskEnv, vessel: str, target: str) -> torch.Tensor:
    """[N] the share of the pieces that started in ``vessel`` that now lie in container ``target``."""
    from gendex_envs.success import in_container

    names = pieces(env, vessel)
    return torch.stack([in_container(env, n, target) for n in names], dim=-1).float().mean(dim=-1)


def lay_pieces(spec: TaskSpec, vessel: str, piece_asset: str, count: int,
               names: Sequence[str] | None = None) -> TaskSpec:
    """``spec`` with ``count`` pieces of catalog asset ``piece_asset`` laid in its object ``vessel`` where that
    stands (its position, turn about the vertical and scale; :func:`fill_layout`), as objects named ``names`` (the
    vessel's pieces before, which they replace; by default ``<piece_asset>_<k>``, the first free k). TaskSpecError
    if the vessel is not an object of ``spec``, the asset is not a piece (tag :data:`POURABLE_TAG`), ``count`` is
    outside 1..:data:`MAX_PIECES` or the pieces do not fit below the vessel's rim."""
    from gendex_envs.assets.catalog import get_asset
    from gendex_envs.spec import ObjectSpec

    by_name = {o.name: o for o in spec.objects}
    if vessel not in by_name:
        raise TaskSpecError(f"cannot fill {vessel!r}: it is not an object of task {spec.name!r} ({sorted(by_name)})")
    piece = get_asset(piece_asset)
    if POURABLE_TAG not in piece.tags:
        raise TaskSpecError(f"cannot fill {vessel!r} with {piece_asset!r}: a vessel holds loose pieces, catalog assets "
                            f"tagged {POURABLE_TAG!r} (e.g. bead, marble)")
    if not 1 <= count <= MAX_PIECES:
        raise TaskSpecError(f"cannot fill {vessel!r} with {count} pieces: 1 to {MAX_PIECES} fill one vessel")
    v = by_name[vessel]
    try:
        laid = fill_layout(get_asset(v.asset), piece, count, v.scale)
    except ValueError as exc:
        raise TaskSpecError(f"cannot fill {vessel!r} ({v.asset} at scale {v.scale:g}): {exc}") from None
    kept = [o for o in spec.objects if o.name not in set(names or ())]
    taken = {o.name for o in kept}
    if names is None or len(names) != count:
        fresh = (f"{piece_asset}_{k}" for k in range(count + len(taken) + 1))
        names = [n for n in fresh if n not in taken][:count]
    w, _, _, z = v.quat_wxyz
    yaw = 2.0 * math.atan2(z, w)  # a vessel stands upright: its turn about the vertical
    c, s = math.cos(yaw), math.sin(yaw)
    x0, y0, z0 = v.pos_m
    pieces_ = [ObjectSpec(name=n, asset=piece_asset, pos_m=(round(x0 + c * dx - s * dy, 4),
                                                             round(y0 + s * dx + c * dy, 4), round(z0 + dz, 4)))
               for n, (dx, dy, dz) in zip(names, laid, strict=True)]
    return dataclasses.replace(spec, objects=(*kept, *pieces_))


def spec_fills(spec: TaskSpec) -> dict[str, tuple[str, ...]]:
    """The objects of ``spec`` that hold pieces, each with its pieces' names (:func:`spec_pieces`)."""
    from gendex_envs.assets.catalog import get_asset

    records = {o.name: get_asset(o.asset) for o in spec.objects}
    out = {}
    for o in spec.objects:
        if POURABLE_TAG not in records[o.name].tags and "container" in records[o.name].tags:
            found = spec_pieces(spec, records, o.name)
            if found:
                out[o.name] = found
    return out


def refill(spec: TaskSpec, fills: Mapping[str, Sequence[str]]) -> TaskSpec:
    """``spec`` with the pieces of each vessel of ``fills`` (:func:`spec_fills` of the spec before an edit) laid
    again where the vessel now stands: a vessel moved, turned or scaled carries its pieces, as at reset."""
    by_name = {o.name: o for o in spec.objects}
    for vessel, names in fills.items():
        if vessel in by_name and names and names[0] in by_name:
            spec = lay_pieces(spec, vessel, by_name[names[0]].asset, len(names), names)
    return spec
