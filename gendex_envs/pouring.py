"""The ``poured`` condition's pieces: the loose things (catalog tag ``pourable``: beads, marbles) that start in a
vessel, and the share of them that now lie in a container.

A piece *starts in* a vessel as any object starts in a container (:func:`gendex_envs.placement.starts_in`: raised off
the table over its footprint); the spec lists each piece as its own object, so every piece is a rigid body the
simulator moves, and a pour is counted only where the pieces really fell into the target. A piece counts as in the
target by the ``inside`` condition's own test (:func:`gendex_envs.success.in_container`), so "poured" and "inside"
never disagree about one bead.
"""

from __future__ import annotations

import math
import weakref
from typing import TYPE_CHECKING

import torch

from gendex_envs.errors import TaskSpecError
from gendex_envs.placement import starts_in

if TYPE_CHECKING:  # pragma: no cover
    from gendex_envs.task_env import TaskEnv

POURABLE_TAG = "pourable"
"""Catalog tag of a loose piece a vessel pours (:mod:`gendex_envs.assets.procedural_pouring`)."""

RING_FRACTION = 0.4
"""Pieces are laid on a ring this fraction of the vessel's half width from its axis (its foot is narrower than its
mouth)."""
PIECE_GAP_M = 0.0015
"""Gap between neighbouring pieces of a layer, and between layers, as laid (they settle at the first steps)."""

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
