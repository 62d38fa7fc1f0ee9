"""The on-disk asset library: ``gendex_envs/assets/data/<group>/manifest.json`` plus the files each entry names.

Every asset is stored at real-world metric scale in its **asset frame**: z up, origin on the bounding box's
vertical axis at the asset's lowest point in its stable rest pose (so placing the origin on the table top rests
it there). Files are written once by the generator scripts (``python -m gendex_envs.assets.build``) and committed;
nothing is computed or downloaded when an env is built.

Rigid assets (``kind: rigid``) have a visual mesh and a collision file holding one ``o`` block per convex hull
(loaded with SAPIEN's ``load_multiple_collisions_from_file``). Articulated assets (``kind: articulated``) have a
URDF whose collision shapes are all convex, and a :class:`JointEntry` per movable joint with its semantics.
"""

from __future__ import annotations

import json
import logging
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Literal

import dacite

from gendex_envs.atomic_io import write_json
from gendex_envs.errors import AssetNotFoundError

log = logging.getLogger(__name__)

DATA_DIR = Path(__file__).resolve().parent / "data"
"""Root of the shipped library; each subfolder with a manifest.json is one group (e.g. ``objects``)."""
MANIFEST = "manifest.json"


@dataclass(frozen=True)
class JointEntry:
    """One movable joint of an articulated asset, with what it means."""

    name: str
    """Joint name in the URDF."""
    type: Literal["revolute", "prismatic"]
    limits: tuple[float, float]
    """Lower and upper limit (rad or m) at scale 1."""
    closed_qpos: float
    """Joint value meaning "closed" / "off"."""
    open_qpos: float
    """Joint value meaning "open" / "on" (the target of an opening task)."""
    handle_link: str
    """URDF link carrying the handle that operates this joint."""
    handle_point_m: tuple[float, float, float]
    """Centre of the handle's grip, in the handle link's frame at scale 1 (m)."""
    holds_m: tuple[tuple[float, float, float], tuple[float, float, float]] | None = None
    """The space the handle link holds things in (a drawer's bin: its floor's top to its walls' top), as the (low,
    high) corners of a box in that link's frame at scale 1 (m); None for a link that holds nothing (a door, a lid).
    An ``inside`` condition with this joint checks it (:func:`gendex_envs.holds.in_holds`)."""
    link_origin_m: tuple[float, float, float] | None = None
    """Where a joint with ``holds_m`` puts its link's frame in the asset frame at qpos 0 (m, scale 1; a drawer slides
    it along -x by its qpos): what an object set in the drawer is placed by before the scene is built."""
    detents: tuple[float, ...] | None = None
    """Rest positions a spring pulls the joint towards, as fractions of the way from closed (0) to open (1): the
    nearest one pulls (:mod:`gendex_envs.detents`). ``(0.0,)``: a momentary button that springs back; ``(0.0, 1.0)``:
    a switch or a latching button that snaps to whichever side it was pushed past the middle. None: no spring."""
    spring: float | None = None
    """Stiffness of the detent spring at scale 1 (N/m for a prismatic joint, N·m/rad for a revolute one)."""
    friction_limit: float | None = None
    """Dry friction the simulation applies (N for a prismatic joint, N·m for a revolute one; unscaled at any object
    scale): the joint stays where it was left until pushed harder than this, and resists with this much while it
    moves (a screw cap's thread). None: only the URDF's damping (SAPIEN's URDF loader drops the URDF's friction)."""


@dataclass(frozen=True)
class AssetEntry:
    """One asset as stored in a manifest (paths relative to the manifest's folder)."""

    id: str
    """Unique id, snake_case (``^[a-z][a-z0-9_]*$``)."""
    category: str
    """What it is: ``apple``, ``mug``, ``cabinet``, ... (articulated variants share a category)."""
    kind: Literal["rigid", "articulated"]
    source: str
    """Where the geometry comes from (generator name, or package and file)."""
    licence: str
    """SPDX-style licence of the shipped files."""
    tags: tuple[str, ...]
    """Semantic tags: graspable, container, tableware, food, fruit, ball, tool, utensil, box, articulated, ..."""
    bbox_min_m: tuple[float, float, float]
    bbox_max_m: tuple[float, float, float]
    """Axis-aligned bounds in the asset frame at scale 1 (bbox_min_m z is 0 by the frame convention)."""
    mass_kg: float
    """Real-world mass at scale 1 (articulated: all links together)."""
    friction: float
    """Static friction coefficient (dynamic = 0.8 x static)."""
    visual: str | None = None
    """Rigid: visual mesh file."""
    collision: str | None = None
    """Rigid: collision file, one ``o`` block per convex hull."""
    volume_m3: float | None = None
    """Rigid: total volume of the collision hulls at scale 1 (density = mass / volume)."""
    rgba: tuple[float, float, float, float] = (0.7, 0.7, 0.7, 1.0)
    """Base colour of the visual mesh."""
    urdf: str | None = None
    """Articulated: the URDF file."""
    fixed_base: bool = True
    """Articulated: the root link is fixed to the world (cabinets, ovens) or free (laptops, boxes)."""
    joints: tuple[JointEntry, ...] = ()
    """Articulated: movable joints with semantics; the first one is the main joint."""
    rest_quat_wxyz: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    """Stable rest orientation (the files are already stored in it, so this is identity unless noted)."""
    params: dict[str, float | str] = field(default_factory=dict)
    """Generator parameters (sizes, handle style, door side, seed) for reproducibility."""

    @property
    def size_m(self) -> tuple[float, float, float]:
        return tuple(float(b - a) for a, b in zip(self.bbox_min_m, self.bbox_max_m, strict=True))


_CONFIG = dacite.Config(strict=True, cast=[tuple])


def read_manifest(path: Path) -> list[AssetEntry]:
    """Parse a manifest.json into entries (strict: unknown keys are errors)."""
    raw = json.loads(Path(path).read_text())
    if not isinstance(raw, dict) or not isinstance(raw.get("assets"), list):
        raise AssetNotFoundError(f"{path}: a manifest is a JSON object with an 'assets' list")
    entries = []
    for i, item in enumerate(raw["assets"]):
        try:
            entries.append(dacite.from_dict(AssetEntry, item, config=_CONFIG))
        except dacite.DaciteError as exc:
            raise AssetNotFoundError(f"{path}: assets[{i}] ({item.get('id', '?')}): {exc}") from exc
    return entries


def write_manifest(path: Path, entries: list[AssetEntry], note: str = "") -> None:
    """Write entries atomically (temp file, then rename)."""
    payload = {"note": note, "assets": [asdict(e) for e in sorted(entries, key=lambda e: e.id)]}
    write_json(path, payload, indent=1)


def shipped_manifests() -> list[Path]:
    return sorted(DATA_DIR.glob(f"*/{MANIFEST}"))
