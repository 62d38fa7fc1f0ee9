"""The procedural object library (gendex_envs/assets/data/objects): shipped files, exact convex decomposition,
asset frame, real-world sizes and masses, open container cavities, and byte-identical rebuilds. No simulator."""

from __future__ import annotations

import re
from functools import cache

import numpy as np
import pytest
import trimesh
from hulls import inside_hulls

from gendex_envs.assets import build_objects
from gendex_envs.assets.manifest import DATA_DIR, MANIFEST, read_manifest
from gendex_envs.assets.procedural import MAX_HULL_FACES, revolve_pts, tube, vessel

OBJECTS = DATA_DIR / "objects"
ENTRIES = read_manifest(OBJECTS / MANIFEST)
BY_ID = {e.id: e for e in ENTRIES}
IDS = sorted(BY_ID)
CONTAINERS = [e.id for e in ENTRIES if "container" in e.tags]
VESSELS = [e.id for e in ENTRIES if "container" in e.tags and "seal0_x" in e.params]
"""Containers that are solids of revolution (their walls sealed by overlapping wedges)."""
OPEN_BOXES = [e.id for e in ENTRIES if "container" in e.tags and e.params.get("material")
              and e.source.endswith("(trimesh primitives)")]
TAGS = {"graspable", "container", "tableware", "food", "fruit", "ball", "tool", "utensil", "box", "block", "toy",
        "kitchenware", "surface", "handover", "marker", "peg", "holder", "insert", "wiper", "spill", "wipe_area",
        "hangable", "hook", "hang_on", "pourer", "pourable", "bead", "vegetable", "household", "office", "toiletry",
        "chess"}


def _parse_obj(path) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """(name, vertices, faces) per ``o`` block; face indices are global in the file, returned block-local."""
    blocks, verts = [], []
    for line in open(path):
        if line.startswith("o "):
            blocks.append([line[2:].strip(), len(verts), []])
        elif line.startswith("v "):
            verts.append([float(v) for v in line.split()[1:4]])
        elif line.startswith("f "):
            blocks[-1][2].append([int(i) - 1 for i in line.split()[1:4]])
    verts = np.asarray(verts)
    out = []
    for k, (name, start, faces) in enumerate(blocks):
        end = blocks[k + 1][1] if k + 1 < len(blocks) else len(verts)
        faces = np.asarray(faces) - start
        assert faces.min() >= 0 and faces.max() < end - start, f"{path}: block {name} indexes outside itself"
        out.append((name, verts[start:end], faces))
    return out


@cache
def _hulls(asset_id: str) -> list[trimesh.Trimesh]:
    blocks = _parse_obj(OBJECTS / BY_ID[asset_id].collision)
    assert [b[0] for b in blocks] == [f"hull_{k}" for k in range(len(blocks))]
    return [trimesh.Trimesh(v, f, process=False) for _, v, f in blocks]


@cache
def _visual(asset_id: str) -> trimesh.Trimesh:
    blocks = _parse_obj(OBJECTS / BY_ID[asset_id].visual)
    assert len(blocks) == 1
    return trimesh.Trimesh(blocks[0][1], blocks[0][2], process=False)


def _size(asset_id):
    return np.array(BY_ID[asset_id].size_m)


# ------------------------------------------------------------------------------------------------ manifest
def test_library_is_complete_and_well_formed():
    assert len(ENTRIES) >= 44
    assert len(IDS) == len(ENTRIES)
    for e in ENTRIES:
        assert re.fullmatch(r"[a-z][a-z0-9_]*", e.id), e.id
        assert e.kind == "rigid" and e.licence == "Apache-2.0" and e.source.startswith("gendex procedural")
        assert set(e.tags) <= TAGS and {"graspable", "surface", "handover", "insert", "wipe_area",
                                        "hang_on", "pourable", "container"} & set(e.tags), (e.id, e.tags)
        files = e.params.get("variant_of", e.id)  # a colour variant uses its base's mesh files
        assert e.visual == f"{files}/visual.obj" and e.collision == f"{files}/collision.obj"
        assert files == e.id or ("variant_of" not in BY_ID[files].params and BY_ID[files].mass_kg == e.mass_kg)
        assert all(0.0 <= c <= 1.0 for c in e.rgba)
    for must in ("apple", "banana", "tennis_ball", "golf_ball", "mug", "bowl", "plate", "cracker_box", "hammer",
                 "spoon", "fork", "knife", "sponge", "dice", "toy_duck", "scissors", "wrench"):
        assert must in BY_ID


@pytest.mark.parametrize("asset_id", IDS)
def test_files_exist(asset_id):
    e = BY_ID[asset_id]
    assert (OBJECTS / e.visual).is_file() and (OBJECTS / e.collision).is_file()


@pytest.mark.parametrize("asset_id", IDS)
def test_mass_friction_density_plausible(asset_id):
    e = BY_ID[asset_id]
    assert 0.005 <= e.mass_kg <= 1.5
    assert 0.5 <= e.friction <= 1.2
    density = e.mass_kg / e.volume_m3
    assert 50 <= density <= 9000, density  # foam sponge ... solid steel


# ------------------------------------------------------------------------------------------------ geometry
@pytest.mark.parametrize("asset_id", IDS)
def test_every_hull_is_convex_and_physx_sized(asset_id):
    hulls = _hulls(asset_id)
    assert hulls
    for k, h in enumerate(hulls):
        assert h.is_watertight and h.volume > 0, (asset_id, k)
        assert trimesh.convex.is_convex(h), (asset_id, k)
        assert abs(h.volume - trimesh.convex.convex_hull(h.vertices).volume) <= 1e-6 * h.volume, (asset_id, k)
        assert len(h.faces) <= MAX_HULL_FACES, (asset_id, k)
    assert sum(h.volume for h in hulls) == pytest.approx(BY_ID[asset_id].volume_m3, rel=1e-5)


@pytest.mark.parametrize("asset_id", IDS)
def test_asset_frame_and_bbox(asset_id):
    e = BY_ID[asset_id]
    lo, hi = _visual(asset_id).bounds
    np.testing.assert_allclose(lo, e.bbox_min_m, atol=1e-9)
    np.testing.assert_allclose(hi, e.bbox_max_m, atol=1e-9)
    assert e.bbox_min_m[2] == 0.0
    assert abs(lo[0] + hi[0]) <= 2e-6 and abs(lo[1] + hi[1]) <= 2e-6  # footprint centred on the origin
    # the collision geometry rests where the visual does and does not stick out of it
    pts = np.vstack([h.vertices for h in _hulls(asset_id)])
    assert 0.0 <= pts[:, 2].min() <= 1e-3
    assert np.all(pts.min(0) >= lo - 2e-3) and np.all(pts.max(0) <= hi + 2e-3)


def _diameter(asset_id):
    return float(_size(asset_id)[:2].max())


@pytest.mark.parametrize(("asset_id", "measure", "lo", "hi"), [
    ("apple", _diameter, 0.06, 0.09),
    ("orange", _diameter, 0.065, 0.09),
    ("tennis_ball", lambda i: _size(i).min(), 0.065, 0.069),
    ("tennis_ball", lambda i: _size(i).max(), 0.065, 0.069),
    ("golf_ball", lambda i: _size(i).max(), 0.042, 0.044),
    ("baseball", lambda i: _size(i).max(), 0.072, 0.076),
    ("softball", lambda i: _size(i).max(), 0.094, 0.098),
    ("mug", lambda i: _size(i)[2], 0.08, 0.11),
    ("banana", lambda i: _size(i).max(), 0.17, 0.22),
    ("can", lambda i: _size(i)[2], 0.12, 0.125),
    ("can", _diameter, 0.065, 0.067),
    ("tuna_can", _diameter, 0.083, 0.085),
    ("bowl", _diameter, 0.14, 0.17),
    ("plate", _diameter, 0.2, 0.28),
    ("dice", lambda i: _size(i).max(), 0.0159, 0.0161),
    ("hammer", lambda i: _size(i).max(), 0.28, 0.36),
    ("spoon", lambda i: _size(i).max(), 0.16, 0.22),
])
def test_real_world_sizes(asset_id, measure, lo, hi):
    assert lo <= measure(asset_id) <= hi


@pytest.mark.parametrize(("asset_id", "size"), [("cracker_box", (0.16, 0.06, 0.21)), ("sugar_box", (0.09, 0.04, 0.175)),
                                                ("pudding_box", (0.089, 0.035, 0.11)), ("sponge", (0.09, 0.06, 0.03)),
                                                ("block_small", (0.04,) * 3), ("rubiks_cube", (0.057,) * 3)])
def test_box_sizes_exact(asset_id, size):
    np.testing.assert_allclose(_size(asset_id), size, atol=1e-6)


def test_lying_tools_are_flat():
    for asset_id in ("hammer", "screwdriver", "spatula", "marker", "scissors", "wrench", "spoon", "fork", "knife"):
        s = _size(asset_id)
        assert s[2] < 0.04 and s[2] < 0.3 * s[:2].max(), asset_id


# ------------------------------------------------------------------------------------------------ containers
def test_containers_present():
    assert {"mug", "cup", "bowl", "bowl_large", "pitcher", "jar", "pot", "wine_glass"} <= set(CONTAINERS)


@pytest.mark.parametrize("asset_id", CONTAINERS)
def test_container_cavity_is_open_and_floored(asset_id):
    p, hulls = BY_ID[asset_id].params, _hulls(asset_id)
    x, y, floor, rim = p["cavity_x"], p["cavity_y"], p["cavity_z"], p["rim_z"]
    assert rim - floor > 0.02
    axis = np.column_stack([np.full(20, x), np.full(20, y), np.linspace(floor + 0.01, rim - 0.003, 20)])
    assert not inside_hulls(hulls, axis).any(), "the cavity is filled"
    assert not inside_hulls(hulls, [[x, y, floor + 0.01]]).any()
    assert inside_hulls(hulls, [[x, y, floor - 0.002]]).all(), "no floor under the cavity"


@pytest.mark.parametrize("asset_id", VESSELS)
def test_container_wall_has_no_gaps(asset_id):
    """Sweep each wall mid-surface probe around the axis: every point must be inside some hull, with 1 mm to
    spare radially (the wedges overlap, so nothing slips between them)."""
    p, hulls = BY_ID[asset_id].params, _hulls(asset_id)
    seals = sorted({k[:-2] for k in p if re.fullmatch(r"seal\d+_x", k)})
    assert seals
    theta = np.linspace(0, 2 * np.pi, 361)[:-1]
    for s in seals:
        r = np.hypot(p[f"{s}_x"] - p["cavity_x"], p[f"{s}_y"] - p["cavity_y"])
        for dr in (-0.001, 0.0, 0.001):
            ring = np.column_stack([p["cavity_x"] + (r + dr) * np.cos(theta), p["cavity_y"] + (r + dr) * np.sin(theta),
                                    np.full(len(theta), p[f"{s}_z"])])
            assert inside_hulls(hulls, ring).all(), (s, dr)


def test_vessels_and_open_boxes_are_every_container():
    assert sorted(VESSELS + OPEN_BOXES) == sorted(CONTAINERS)
    assert {"basket", "baking_dish", "storage_bin"} <= set(OPEN_BOXES)


@pytest.mark.parametrize("asset_id", OPEN_BOXES)
def test_open_box_walls_are_closed(asset_id):
    """A ring of points half-way up the walls, in the middle of their thickness, all round: every point is inside a
    hull (the corners included), and none of the points 1 cm further in is."""
    e, hulls = BY_ID[asset_id], _hulls(asset_id)
    (x0, y0, _), (x1, y1, h) = e.bbox_min_m, e.bbox_max_m
    wall = min(np.ptp(v.vertices[:, :2], axis=0).min() for v in hulls[1:])  # hull 0 is the floor
    for inset, inside in ((wall / 2, True), (wall + 0.01, False)):
        xs, ys = np.linspace(x0 + inset, x1 - inset, 60), np.linspace(y0 + inset, y1 - inset, 40)
        ring = np.vstack([np.column_stack([xs, np.full(60, y)]) for y in (ys[0], ys[-1])]
                         + [np.column_stack([np.full(40, x), ys]) for x in (xs[0], xs[-1])])
        pts = np.column_stack([ring, np.full(len(ring), h / 2)])
        assert inside_hulls(hulls, pts).all() == inside and (inside or not inside_hulls(hulls, pts).any()), inset


def test_mug_has_a_handle():
    hulls = _hulls("mug")
    p = BY_ID["mug"].params
    x_out = BY_ID["mug"].bbox_max_m[0]
    assert x_out - p["cavity_x"] > 0.06  # the handle reaches well beyond the 4.1 cm body radius
    grip = [[x_out - 0.005, p["cavity_y"], p["cavity_z"] + 0.04]]
    assert inside_hulls(hulls, grip).all()


# ------------------------------------------------------------------------------------------------ building blocks
def test_vessel_decomposition_matches_analytic_volume():
    """A straight cup: base disc + 16 wedges approximate the exact solid within a few percent, and cavity is empty."""
    R, H, t, f = 0.04, 0.1, 0.005, 0.008
    vis, hulls, info = vessel([(0, 0), (R, 0), (R, H)], t, f, wedges=16)
    meshes = [trimesh.convex.convex_hull(h) for h in hulls]
    assert all(trimesh.convex.is_convex(m) for m in meshes)
    exact = np.pi * R**2 * f + np.pi * (R**2 - (R - t) ** 2) * (H - f)
    assert vis.is_watertight
    assert vis.volume == pytest.approx(exact, rel=0.03)
    assert meshes[0].volume == pytest.approx(np.pi * R**2 * f, rel=0.03)
    ring = np.pi * (R**2 - (R - t) ** 2)
    wall = sum(m.volume for m in meshes[1:])  # wedges overlap by 2 x 12 % and fill the inner chord of their arc
    assert ring * (H - f) < wall < 1.5 * ring * H
    around = np.linspace(0, 2 * np.pi, 200)
    assert inside_hulls(meshes, revolve_pts([[R - t / 2, H / 2]], around)).all()  # the wall is closed
    assert not inside_hulls(meshes, revolve_pts([[R - t - 0.0015, H / 2]], around)).any()  # chords stay < 1.5 mm
    assert not inside_hulls(meshes, revolve_pts([[R + 0.0005, H / 2]], around)).any()
    assert not inside_hulls(meshes, [[0, 0, f + 0.01], [0.02, 0.0, 0.05]]).any()
    assert info["floor_z"] == f and info["top_z"] == H


def test_tube_chain_covers_its_path():
    path = np.column_stack([np.linspace(0, 0.1, 9), np.zeros(9), np.full(9, 0.01)])
    vis, hulls = tube(path, 0.01, 0.01, hull_every=2)
    assert vis.is_watertight and vis.volume > 0 and len(hulls) == 4
    meshes = [trimesh.convex.convex_hull(h) for h in hulls]
    assert inside_hulls(meshes, path).all()


# ------------------------------------------------------------------------------------------------ determinism
def test_rebuild_is_byte_identical(tmp_path):
    entries = build_objects.build(tmp_path)
    assert sorted(e.id for e in entries) == IDS
    for name in (MANIFEST, "LICENSE"):
        assert (tmp_path / name).read_bytes() == (OBJECTS / name).read_bytes(), name
    for e in entries:
        for rel in (e.visual, e.collision):
            assert (tmp_path / rel).read_bytes() == (OBJECTS / rel).read_bytes(), rel


def test_library_is_small():
    size = sum(f.stat().st_size for f in OBJECTS.rglob("*") if f.is_file())
    assert size < 6e6
