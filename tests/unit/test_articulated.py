"""The procedural articulated library: URDFs load in SAPIEN and match their manifest entries' joint semantics."""

from __future__ import annotations

import filecmp
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
import sapien
from sapien import physx

from gendex_envs.assets.build_articulated import DEFAULT_OUT, build
from gendex_envs.assets.manifest import MANIFEST, AssetEntry, read_manifest

ENTRIES = read_manifest(DEFAULT_OUT / MANIFEST)
FRONT_CATEGORIES = {"cabinet", "drawer_chest", "microwave", "oven", "dishwasher", "refrigerator", "laptop",
                    "box_with_lid", "trash_can", "knob"}
"""Categories operated from the front: the grip lies in front (-x) of the body."""
_RING = np.stack([np.zeros(16), np.cos(np.arange(16) * np.pi / 8), np.sin(np.arange(16) * np.pi / 8)], axis=1)


def _load(entry: AssetEntry, fix_root: bool = True, ground: bool = False):
    scene = sapien.Scene()
    scene.set_timestep(1 / 120)
    if ground:
        scene.add_ground(0.0)
    loader = scene.create_urdf_loader()
    loader.fix_root_link = fix_root
    art = loader.load(str(DEFAULT_OUT / entry.urdf))
    assert isinstance(art, physx.PhysxArticulation), f"{entry.id}: expected one articulation"
    art.set_qpos(np.array([j.closed_qpos for j in entry.joints]))  # also computes the link poses
    return scene, art


def _shape_points(shape) -> np.ndarray:
    if isinstance(shape, physx.PhysxCollisionShapeBox):
        h = np.asarray(shape.half_size)
        return np.array([[x, y, z] for x in (-h[0], h[0]) for y in (-h[1], h[1]) for z in (-h[2], h[2])])
    if isinstance(shape, physx.PhysxCollisionShapeSphere):
        return np.concatenate([np.eye(3), -np.eye(3)]) * shape.radius
    if isinstance(shape, physx.PhysxCollisionShapeCylinder):  # SAPIEN cylinders run along local x
        ring = _RING * shape.radius
        return np.concatenate([ring - [shape.half_length, 0, 0], ring + [shape.half_length, 0, 0]])
    raise AssertionError(f"unexpected (non-primitive) collision shape {type(shape).__name__}")


def _link_points(link) -> np.ndarray:
    out = []
    for shape in link.collision_shapes:
        m = (link.entity_pose * shape.local_pose).to_transformation_matrix()
        out.append(_shape_points(shape) @ m[:3, :3].T + m[:3, 3])
    return np.concatenate(out)


def _inside(shape, p_local: np.ndarray, tol: float) -> bool:
    if isinstance(shape, physx.PhysxCollisionShapeBox):
        return bool(np.all(np.abs(p_local) <= np.asarray(shape.half_size) + tol))
    if isinstance(shape, physx.PhysxCollisionShapeSphere):
        return bool(np.linalg.norm(p_local) <= shape.radius + tol)
    return bool(abs(p_local[0]) <= shape.half_length + tol and np.linalg.norm(p_local[1:]) <= shape.radius + tol)


def _links(art) -> dict:
    return {link.name: link for link in art.links}


def test_categories_and_variants():
    counts = Counter(e.category for e in ENTRIES)
    assert len(counts) >= 10, counts
    assert all(n >= 2 for n in counts.values()), counts
    assert len({e.id for e in ENTRIES}) == len(ENTRIES)
    for e in ENTRIES:
        assert e.kind == "articulated" and e.urdf and e.joints and "articulated" in e.tags
        assert e.bbox_min_m[2] == 0.0 and abs(e.bbox_min_m[1] + e.bbox_max_m[1]) < 1e-6, e.id  # bottom centre


@pytest.mark.parametrize("entry", ENTRIES, ids=lambda e: e.id)
def test_urdf_matches_manifest(entry: AssetEntry):
    _, art = _load(entry)
    active = art.get_active_joints()
    assert [j.name for j in active] == [j.name for j in entry.joints]
    links = _links(art)
    body = art.root
    lo_b, hi_b = _link_points(body).min(0), _link_points(body).max(0)
    for joint, spec in zip(active, entry.joints, strict=True):
        assert joint.type.startswith(spec.type), (joint.type, spec.type)
        np.testing.assert_allclose(joint.get_limits()[0], spec.limits, atol=1e-5)
        assert spec.limits[0] <= spec.closed_qpos < spec.open_qpos <= spec.limits[1]
        assert spec.handle_link in links and joint.child_link.name == spec.handle_link
        handle = links[spec.handle_link]
        grip = handle.entity_pose * sapien.Pose(spec.handle_point_m)
        # the grip point lies on (within 3 mm of) one of the handle link's collision shapes
        assert any(_inside(s, (handle.entity_pose * s.local_pose).inv().to_transformation_matrix()[:3, :3]
                           @ (grip.p - (handle.entity_pose * s.local_pose).p), 0.003)
                   for s in handle.collision_shapes), f"{entry.id}: grip point not on the handle"
        low = 0.015 if entry.category == "laptop" else 0.05  # a closed laptop's lid edge is ~2 cm up
        assert low <= grip.p[2] <= 0.8, f"{entry.id}: grip height {grip.p[2]:.3f}"
        if joint is not active[0]:
            continue  # secondary joints (a dishwasher rack) sit inside the body until the main joint opens
        if entry.category in FRONT_CATEGORIES:
            assert grip.p[0] < lo_b[0], f"{entry.id}: grip x {grip.p[0]:.3f} not in front of body {lo_b[0]:.3f}"
        else:
            assert np.any(grip.p < lo_b) or np.any(grip.p > hi_b), f"{entry.id}: grip inside the body"
    pts = np.concatenate([_link_points(link) for link in art.links])
    np.testing.assert_allclose(pts.min(0), entry.bbox_min_m, atol=0.005)
    np.testing.assert_allclose(pts.max(0), entry.bbox_max_m, atol=0.005)
    assert sum(link.mass for link in art.links) == pytest.approx(entry.mass_kg, rel=1e-4)


def _settle(scene, art, qpos: np.ndarray, targets: np.ndarray, stiffness: float, seconds: float) -> np.ndarray:
    art.set_qpos(qpos)
    art.set_qvel(np.zeros_like(qpos))
    for j, t in zip(art.get_active_joints(), targets, strict=True):
        if not stiffness:
            j.set_friction(0.0)  # PhysX joint friction scales with the joint load; test gravity alone
        j.set_drive_properties(stiffness, 100.0 if stiffness else 0.0)
        j.set_drive_target(float(t))
    for _ in range(int(seconds * 120)):
        scene.step()
    return np.asarray(art.get_qpos())


@pytest.mark.parametrize("entry", ENTRIES, ids=lambda e: e.id)
def test_joints_drive_open_and_rest_closed(entry: AssetEntry):
    scene, art = _load(entry)
    closed = np.array([j.closed_qpos for j in entry.joints])
    for i, spec in enumerate(entry.joints):
        start = closed.copy()
        if i > 0:  # secondary joints (e.g. a dishwasher rack) are operated with the main one open
            start[0] = entry.joints[0].open_qpos
        target = start.copy()
        target[i] = spec.open_qpos
        q = _settle(scene, art, start, target, 1000.0, 2.0)
        assert abs(q[i] - spec.open_qpos) <= 0.1 * abs(spec.open_qpos - spec.closed_qpos), (spec.name, q)
    # undriven and frictionless, gravity alone keeps every joint closed (bottom-hinged doors, lids rest on the limit)
    q = _settle(scene, art, closed, closed, 0.0, 1.0)
    np.testing.assert_allclose(q, closed, atol=0.02, err_msg=entry.id)


@pytest.mark.parametrize("entry", [e for e in ENTRIES if not e.fixed_base], ids=lambda e: e.id)
def test_free_base_rests_upright(entry: AssetEntry):
    scene, art = _load(entry, fix_root=False, ground=True)
    for _ in range(120):
        scene.step()
    assert abs(art.root_pose.p[2]) < 0.005 and abs(art.root_pose.q[0]) > 0.999, art.root_pose
    assert abs(art.get_qpos()[0] - entry.joints[0].closed_qpos) < 0.02


def test_rebuild_is_byte_identical(tmp_path: Path):
    written = build(tmp_path)
    assert len(written) == len(ENTRIES) + 2  # URDFs, LICENSE, manifest
    for path in written:
        rel = path.relative_to(tmp_path)
        assert filecmp.cmp(path, DEFAULT_OUT / rel, shallow=False), f"{rel} differs from the shipped file"
    build(tmp_path)
    assert all(filecmp.cmp(p, DEFAULT_OUT / p.relative_to(tmp_path), shallow=False) for p in written)
