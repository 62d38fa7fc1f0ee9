"""PartNet-Mobility models from ManiSkill's asset directory, as articulated :class:`AssetEntry` objects.

Layout read (``<data>`` is :func:`~gendex_envs.assets.user_datasets.common.maniskill_asset_dir`)::

    <data>/partnet_mobility/dataset/<model_id>/mobility_cvx.urdf     # or mobility_fixed.urdf, or mobility.urdf
    <data>/partnet_mobility/meta/info_*_train.json           # optional, user-supplied metadata (same format as below)
    mani_skill/assets/partnet_mobility/meta/info_*_train.json    # shipped with ManiSkill: {model_id: {"scale", ...}}

The URDF is read here (links, joints, geometries; forward kinematics at the closed configuration) to measure the
model, its joints and their handles without SAPIEN. Units and frames (``file_scale``, ``origin_dz_m``): see
:mod:`gendex_envs.assets.user_datasets`.
"""

from __future__ import annotations

import logging
import math
import re
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gendex_envs.assets.manifest import AssetEntry, JointEntry
from gendex_envs.assets.user_datasets.common import (
    _bounds,
    _dataset_entry,
    _grounded,
    _hull_volume,
    _load_json,
    _load_parts,
    _maniskill_package_meta_dir,
    _number,
    _parts_vertices,
    _snake,
    _tuple3,
    _vec3,
    maniskill_asset_dir,
)
from gendex_envs.errors import AssetNotFoundError

log = logging.getLogger(__name__)

# ---------------------------------------------------------------------------------------------- layout constants
PM_DIR = Path("partnet_mobility") / "dataset"
"""data.py: target_path = ASSET_DIR / "partnet_mobility" / "dataset" / model_id."""
PM_USER_META_DIR = Path("partnet_mobility") / "meta"
PM_URDF_NAMES = ("mobility_cvx.urdf", "mobility_fixed.urdf", "mobility.urdf")
"""partnet_mobility.py: find_urdf_path tries mobility_cvx.urdf then mobility_fixed.urdf; mobility.urdf is the
name in the original PartNet-Mobility release."""
PM_SOURCE = "PartNet-Mobility via ManiSkill asset dir"
PM_LICENCE = "PartNet-Mobility terms (non-commercial research)"
PM_FRICTION = 1.0
"""partnet_mobility.py: material=dict(static_friction=1, dynamic_friction=1, restitution=0)."""
PM_DEFAULT_DENSITY = 1000.0
"""SAPIEN's URDFLoader default density (sapien/wrapper/urdf_loader.py: self._density = 1000)."""
PM_OPEN_FRACTION = 0.8
"""open_qpos = lower + 0.8 x range."""
PM_META_CATEGORY = {"cabinet_drawer": "cabinet", "cabinet_door": "cabinet"}
"""Category of a ManiSkill metadata file ``info_<stem>_<split>.json`` (default: the stem itself)."""
PM_CONTAINERS = frozenset({"cabinet", "bucket", "storage_furniture", "refrigerator", "box", "safe", "microwave",
                           "oven", "dishwasher", "washing_machine", "trash_can", "table"})
PM_PRIORITY_LABELS = ("door", "drawer", "lid", "switch", "handle", "button", "knob")
"""Joints whose moving link has one of these semantic labels come first (the first joint is the main one)."""


# ---------------------------------------------------------------------------------------------- URDF
@dataclass
class _Geom:
    origin: np.ndarray  # 4x4, geometry -> link
    kind: str  # mesh | box | cylinder | sphere
    filename: Path | None = None
    scale: np.ndarray = field(default_factory=lambda: np.ones(3))
    size: tuple[float, ...] = ()
    name: str = ""


@dataclass
class _Link:
    name: str
    visuals: list[_Geom] = field(default_factory=list)
    collisions: list[_Geom] = field(default_factory=list)
    mass: float | None = None


@dataclass
class _Joint:
    name: str
    type: str
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray
    lower: float | None
    upper: float | None


def _floats(text: str | None, n: int, default: Sequence[float], where: str) -> np.ndarray:
    if text is None:
        return np.asarray(default, dtype=float)
    try:
        vals = [float(v) for v in text.split()]
    except ValueError as exc:
        raise AssetNotFoundError(f"{where}: not numbers: {text!r}") from exc
    if len(vals) != n:
        raise AssetNotFoundError(f"{where}: expected {n} numbers, got {text!r}")
    return np.asarray(vals, dtype=float)


def _rpy_matrix(r: float, p: float, y: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _origin(elem: ET.Element | None, where: str) -> np.ndarray:
    t = np.eye(4)
    if elem is not None:
        t[:3, :3] = _rpy_matrix(*_floats(elem.get("rpy"), 3, (0, 0, 0), f"{where} origin rpy"))
        t[:3, 3] = _floats(elem.get("xyz"), 3, (0, 0, 0), f"{where} origin xyz")
    return t


def _find_file(filename: str, urdf_dir: Path) -> Path:
    """Resolve a mesh file name as SAPIEN's URDF loader does (``_try_very_hard_to_find_file``)."""
    if filename.startswith("package://"):
        rel = filename[len("package://"):]
        d = urdf_dir
        while True:
            if (d / rel).is_file():
                return d / rel
            if d == d.parent:
                return urdf_dir / rel
            d = d.parent
    return urdf_dir / filename


def _geom(elem: ET.Element, urdf: Path, where: str) -> _Geom | None:
    g = elem.find("geometry")
    if g is None or len(g) == 0:
        raise AssetNotFoundError(f"{urdf}: {where} has no geometry")
    shape = g[0]
    origin = _origin(elem.find("origin"), f"{urdf}: {where}")
    name = elem.get("name", "")
    if shape.tag == "mesh":
        fname = shape.get("filename")
        if not fname:
            raise AssetNotFoundError(f"{urdf}: {where} mesh has no filename")
        return _Geom(origin, "mesh", _find_file(fname, urdf.parent),
                     _floats(shape.get("scale"), 3, (1, 1, 1), f"{urdf}: {where} mesh scale"), name=name)
    if shape.tag == "box":
        return _Geom(origin, "box", size=tuple(_floats(shape.get("size"), 3, (0, 0, 0), f"{urdf}: {where} box")),
                     name=name)
    if shape.tag in ("cylinder", "capsule"):
        r = _floats(shape.get("radius"), 1, (0,), f"{urdf}: {where} radius")[0]
        h = _floats(shape.get("length"), 1, (0,), f"{urdf}: {where} length")[0]
        return _Geom(origin, "cylinder", size=(r, h + (2 * r if shape.tag == "capsule" else 0.0)), name=name)
    if shape.tag == "sphere":
        return _Geom(origin, "sphere", size=(_floats(shape.get("radius"), 1, (0,), f"{urdf}: {where} radius")[0],),
                     name=name)
    log.debug("%s: %s has unsupported geometry <%s>; ignored", urdf, where, shape.tag)
    return None


def _parse_urdf(urdf: Path) -> tuple[dict[str, _Link], list[_Joint]]:
    try:
        robot = ET.parse(urdf).getroot()
    except (ET.ParseError, OSError) as exc:
        raise AssetNotFoundError(f"{urdf}: cannot parse URDF: {exc}") from exc
    if robot.tag != "robot":
        raise AssetNotFoundError(f"{urdf}: root element is <{robot.tag}>, expected <robot>")
    links: dict[str, _Link] = {}
    for le in robot.findall("link"):
        name = le.get("name")
        if not name:
            raise AssetNotFoundError(f"{urdf}: a <link> has no name")
        link = _Link(name)
        for kind, dest in (("visual", link.visuals), ("collision", link.collisions)):
            for i, ge in enumerate(le.findall(kind)):
                g = _geom(ge, urdf, f"link {name!r} {kind}[{i}]")
                if g is not None:
                    dest.append(g)
        m = le.find("inertial/mass")
        if m is not None and m.get("value") is not None:
            link.mass = float(_floats(m.get("value"), 1, (0,), f"{urdf}: link {name!r} mass")[0])
        links[name] = link
    joints = []
    for je in robot.findall("joint"):
        name, jtype = je.get("name"), je.get("type")
        parent, child = je.find("parent"), je.find("child")
        where = f"{urdf}: joint {name!r}"
        if not name or not jtype or parent is None or child is None:
            raise AssetNotFoundError(f"{where}: needs a name, a type, <parent> and <child>")
        p, c = parent.get("link"), child.get("link")
        if p not in links or c not in links:
            raise AssetNotFoundError(f"{where}: parent {p!r} or child {c!r} is not a link of the URDF")
        axis_e = je.find("axis")
        axis = _floats(axis_e.get("xyz") if axis_e is not None else None, 3, (1, 0, 0), f"{where} axis")
        n = float(np.linalg.norm(axis))
        axis = axis / n if n > 1e-9 else np.array([1.0, 0.0, 0.0])
        lim = je.find("limit")
        lower = upper = None
        if lim is not None and jtype in ("revolute", "prismatic"):
            lower = float(_floats(lim.get("lower"), 1, (0,), f"{where} limit lower")[0])
            upper = float(_floats(lim.get("upper"), 1, (0,), f"{where} limit upper")[0])
            if upper < lower:
                raise AssetNotFoundError(f"{where}: limit upper {upper} < lower {lower}")
        joints.append(_Joint(name, jtype, p, c, _origin(je.find("origin"), where), axis, lower, upper))
    if not links:
        raise AssetNotFoundError(f"{urdf}: no <link>")
    children = [j.child for j in joints]
    if len(set(children)) != len(children):
        raise AssetNotFoundError(f"{urdf}: a link is the child of two joints")
    roots = [n for n in links if n not in set(children)]
    if len(roots) != 1:
        raise AssetNotFoundError(f"{urdf}: expected one root link, found {roots}")
    reached, stack = {roots[0]}, [roots[0]]
    while stack:
        name = stack.pop()
        for j in joints:
            if j.parent == name and j.child not in reached:
                reached.add(j.child)
                stack.append(j.child)
    if len(reached) != len(links):
        raise AssetNotFoundError(f"{urdf}: links not connected to the root {roots[0]!r}: "
                                 f"{sorted(set(links) - reached)}")
    return links, joints


def _closed_q(j: _Joint) -> float:
    if j.type in ("revolute", "prismatic") and j.lower is not None:
        return j.lower
    return 0.0


def _link_poses(links: dict[str, _Link], joints: list[_Joint]) -> dict[str, np.ndarray]:
    """World pose of every link with every movable joint at its closed value (forward kinematics)."""
    by_parent: dict[str, list[_Joint]] = {}
    for j in joints:
        by_parent.setdefault(j.parent, []).append(j)
    root = next(n for n in links if n not in {j.child for j in joints})
    poses = {root: np.eye(4)}
    stack = [root]
    while stack:
        name = stack.pop()
        for j in by_parent.get(name, []):
            motion = np.eye(4)
            q = _closed_q(j)
            if j.type in ("revolute", "continuous"):
                k = j.axis
                kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
                motion[:3, :3] = np.eye(3) + math.sin(q) * kx + (1 - math.cos(q)) * kx @ kx
            elif j.type == "prismatic":
                motion[:3, 3] = j.axis * q
            poses[j.child] = poses[name] @ j.origin @ motion
            stack.append(j.child)
    return poses


class _Meshes:
    """Vertices of the geometries of one URDF, each mesh file read once."""

    def __init__(self) -> None:
        self._cache: dict[Path, list] = {}

    def parts(self, path: Path) -> list:
        if path not in self._cache:
            self._cache[path] = _load_parts(path)
        return self._cache[path]

    def vertices(self, g: _Geom) -> np.ndarray:
        """Vertices of a geometry in its link's frame."""
        if g.kind == "mesh":
            v = _parts_vertices(self.parts(g.filename)) * g.scale
        elif g.kind == "box":
            h = np.asarray(g.size) / 2
            v = np.array([[x, y, z] for x in (-h[0], h[0]) for y in (-h[1], h[1]) for z in (-h[2], h[2])])
        elif g.kind == "cylinder":
            r, h = g.size
            v = np.array([[x, y, z] for x in (-r, r) for y in (-r, r) for z in (-h / 2, h / 2)])
        else:
            r = g.size[0]
            v = np.array([[x, y, z] for x in (-r, r) for y in (-r, r) for z in (-r, r)])
        return v @ g.origin[:3, :3].T + g.origin[:3, 3]

    def volume(self, g: _Geom) -> float:
        if g.kind == "mesh":
            return _hull_volume(self.parts(g.filename)) * float(np.prod(np.abs(g.scale)))
        if g.kind == "box":
            return float(np.prod(g.size))
        if g.kind == "cylinder":
            return math.pi * g.size[0] ** 2 * g.size[1]
        return 4 / 3 * math.pi * g.size[0] ** 3


# ---------------------------------------------------------------------------------------------- PartNet-Mobility
@dataclass
class _PMMeta:
    info: dict
    category: str
    file: Path


def _pm_meta_files(root: Path) -> list[Path]:
    """Shipped ManiSkill metadata first, then the user's (which override it)."""
    files: list[Path] = []
    pkg = _maniskill_package_meta_dir()
    if pkg is not None:
        files += sorted(pkg.glob("info_*.json"))
    user = root / PM_USER_META_DIR
    if user.is_dir():
        files += sorted(user.glob("info_*.json"))
    return files


def _pm_metadata(files: Iterable[Path]) -> dict[str, _PMMeta]:
    out: dict[str, _PMMeta] = {}
    for path in files:
        raw = _load_json(path)
        if not isinstance(raw, dict):
            raise AssetNotFoundError(f"{path}: expected a JSON object mapping model ids to metadata")
        stem = re.sub(r"^info_", "", path.stem)
        stem = re.sub(r"_(train|test|val|valid|validation)$", "", stem)
        category = PM_META_CATEGORY.get(stem, _snake(stem) or "articulated_object")
        for model_id, info in raw.items():
            where = f"{path}: {model_id!r}"
            if not isinstance(info, dict):
                raise AssetNotFoundError(f"{where}: expected an object, got {type(info).__name__}")
            if "scale" in info:
                _number(info["scale"], f"{where}.scale")
            if "density" in info:
                _number(info["density"], f"{where}.density")
            if "bbox" in info:
                bb = info["bbox"]
                if not isinstance(bb, dict) or "min" not in bb or "max" not in bb:
                    raise AssetNotFoundError(f"{where}.bbox: expected {{'min': [x,y,z], 'max': [x,y,z]}}")
                _vec3(bb["min"], f"{where}.bbox.min")
                _vec3(bb["max"], f"{where}.bbox.max")
            if "semantics" in info and not (isinstance(info["semantics"], list)
                                            and all(isinstance(s, list) and len(s) == 3 for s in info["semantics"])):
                raise AssetNotFoundError(f"{where}.semantics: expected a list of [link, joint_kind, label]")
            out[str(model_id)] = _PMMeta(info, category, path)
    return out


def _pm_semantics(model_dir: Path, meta: _PMMeta | None) -> dict[str, str]:
    """Link name -> semantic label, from the metadata (faucets) or the dataset's ``semantics.txt``."""
    labels: dict[str, str] = {}
    sem = model_dir / "semantics.txt"
    if sem.is_file():
        for line in sem.read_text(errors="replace").splitlines():
            parts = line.split()
            if len(parts) >= 3:
                labels[parts[0]] = _snake(parts[2])
    if meta is not None:
        for link, _kind, label in meta.info.get("semantics", []):
            labels[str(link)] = _snake(str(label))
    return labels


def _pm_category(model_dir: Path, meta: _PMMeta | None) -> str:
    if meta is not None:
        return meta.category
    meta_json = model_dir / "meta.json"  # original PartNet-Mobility release: {"model_cat": "StorageFurniture", ...}
    if meta_json.is_file():
        raw = _load_json(meta_json)
        if isinstance(raw, dict) and isinstance(raw.get("model_cat"), str) and _snake(raw["model_cat"]):
            return _snake(raw["model_cat"])
    return "articulated_object"


def _find_urdf(model_dir: Path) -> Path | None:
    return next((model_dir / n for n in PM_URDF_NAMES if (model_dir / n).is_file()), None)


def _pm_entry(model_id: str, model_dir: Path, urdf: Path, meta: _PMMeta | None) -> AssetEntry | None:
    links, joints = _parse_urdf(urdf)
    info = meta.info if meta is not None else {}
    fs = float(info.get("scale", 1.0))
    density = float(info.get("density", PM_DEFAULT_DENSITY))
    meshes = _Meshes()
    missing = sorted({str(g.filename) for lk in links.values() for g in lk.visuals + lk.collisions
                      if g.kind == "mesh" and not g.filename.is_file()})
    if missing:
        log.warning("PartNet-Mobility %s skipped: %s names missing mesh files, e.g. %s", model_id, urdf, missing[0])
        return None
    poses = _link_poses(links, joints)

    # bounds of the whole model at its closed configuration
    if "bbox" in info:
        lo = np.asarray(info["bbox"]["min"], dtype=float) * fs
        hi = np.asarray(info["bbox"]["max"], dtype=float) * fs
    else:
        pts = [meshes.vertices(g) @ poses[lk.name][:3, :3].T + poses[lk.name][:3, 3]
               for lk in links.values() for g in (lk.collisions or lk.visuals)]
        if not pts:
            raise AssetNotFoundError(f"{urdf}: no geometry to measure")
        lo, hi = _bounds(np.concatenate(pts) * fs)
    lo, hi, dz = _grounded(lo, hi)

    labels = _pm_semantics(model_dir, meta)
    entries: list[tuple[int, JointEntry]] = []
    moving: set[str] = set()
    by_parent: dict[str, list[_Joint]] = {}
    for j in joints:
        by_parent.setdefault(j.parent, []).append(j)
    for j in joints:
        if j.type not in ("revolute", "prismatic", "continuous"):
            continue
        stack = [j.child]  # the child and everything below it moves with this joint
        while stack:
            name = stack.pop()
            moving.add(name)
            stack += [c.child for c in by_parent.get(name, [])]
        if j.type == "continuous" or j.lower is None or j.upper is None:
            # unlimited: ManiSkill's TurnFaucet starts such joints at 0 and targets pi/2
            limits, closed, opened = (-math.pi, math.pi), 0.0, math.pi / 2
        else:
            k = fs if j.type == "prismatic" else 1.0
            limits = (j.lower * k, j.upper * k)
            closed, opened = limits[0], limits[0] + PM_OPEN_FRACTION * (limits[1] - limits[0])
        child = links[j.child]
        handle_geoms = [g for g in child.visuals if "handle" in g.name.lower()] or child.collisions
        if handle_geoms:
            hlo, hhi = _bounds(np.concatenate([meshes.vertices(g) for g in handle_geoms]))
            handle = (hlo + hhi) / 2 * fs
        else:
            handle = np.zeros(3)
        label = labels.get(j.child, "")
        prio = PM_PRIORITY_LABELS.index(label) if label in PM_PRIORITY_LABELS else len(PM_PRIORITY_LABELS)
        entries.append((prio, JointEntry(
            name=j.name, type="prismatic" if j.type == "prismatic" else "revolute",
            limits=(float(limits[0]), float(limits[1])), closed_qpos=float(closed), open_qpos=float(opened),
            handle_link=j.child, handle_point_m=_tuple3(handle))))
    entries.sort(key=lambda pe: pe[0])  # stable: URDF order within a priority

    mass = 0.0
    for name in moving:
        lk = links[name]
        if lk.mass:
            mass += lk.mass * fs**3
        else:
            mass += density * sum(meshes.volume(g) for g in lk.collisions) * fs**3
    if mass <= 0:
        mass = 1.0
        log.debug("PartNet-Mobility %s: no mass or collision volume for the moving parts; using 1 kg", model_id)

    category = _pm_category(model_dir, meta)
    tags = ["articulated", category]
    if category in PM_CONTAINERS:
        tags.append("container")
    for name in sorted(moving):
        if labels.get(name) and labels[name] not in tags:
            tags.append(labels[name])
    params: dict[str, float | str] = {"origin_dz_m": dz, "file_scale": fs, "model_id": model_id}
    if meta is not None:
        params["metadata"] = str(meta.file)
    return _dataset_entry(
        "pm", model_id,
        category=category,
        kind="articulated",
        source=PM_SOURCE,
        licence=PM_LICENCE,
        tags=tags,
        lo=lo,
        hi=hi,
        mass=mass,
        friction=PM_FRICTION,
        urdf=str(urdf.resolve()),
        fixed_base=True,
        joints=tuple(je for _, je in entries),
        params=params,
    )


def load_partnet_mobility(root: Path | None = None, *, meta_files: Iterable[Path] | None = None
                          ) -> list[AssetEntry]:
    """PartNet-Mobility models under ``root/partnet_mobility/dataset`` (``root``: ManiSkill's data folder).

    Every ``<model_id>/`` folder holding a URDF (:data:`PM_URDF_NAMES`, in ManiSkill's order of preference) is
    read. Metadata (scale, category, bbox, semantics) comes from ``meta_files`` (default: ManiSkill's shipped
    ``info_*.json`` then the user's ``root/partnet_mobility/meta/info_*.json``); a model without metadata loads at
    file scale 1. Models whose URDF names missing mesh files are skipped with a warning.
    """
    root = Path(root) if root is not None else maniskill_asset_dir()
    dataset = root / PM_DIR
    if not dataset.is_dir():
        log.debug("no PartNet-Mobility data at %s", dataset)
        return []
    metadata = _pm_metadata(_pm_meta_files(root) if meta_files is None else [Path(p) for p in meta_files])
    entries = []
    for model_dir in sorted(d for d in dataset.iterdir() if d.is_dir()):
        urdf = _find_urdf(model_dir)
        if urdf is None:
            log.debug("PartNet-Mobility %s skipped: none of %s in %s", model_dir.name, PM_URDF_NAMES, model_dir)
            continue
        entry = _pm_entry(model_dir.name, model_dir, urdf, metadata.get(model_dir.name))
        if entry is not None:
            entries.append(entry)
    log.debug("PartNet-Mobility: %d models found in %s", len(entries), dataset)
    return entries
