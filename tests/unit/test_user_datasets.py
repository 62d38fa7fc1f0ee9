"""User-supplied YCB / PartNet-Mobility loaders, on a tiny sample written in ManiSkill's layout under tmp_path."""

from __future__ import annotations

import json
import math
import socket
from pathlib import Path

import numpy as np
import pytest
import trimesh

from gendex_envs.assets import user_datasets as ud
from gendex_envs.assets.manifest import AssetEntry, read_manifest, write_manifest
from gendex_envs.assets.user_datasets import common, partnet_mobility
from gendex_envs.errors import AssetNotFoundError

BOX = (0.06, 0.16, 0.21)  # cracker box extents, centred on the origin like ManiSkill's YCB meshes
BOX_DENSITY = 500.0
APPLE_R = 0.08  # file radius; info scale 0.5 -> 4 cm
APPLE_SCALE = 0.5
PM_ID = "99901"  # not an id of ManiSkill's shipped metadata
PM_SCALE = 0.5


@pytest.fixture(autouse=True)
def no_network(monkeypatch):
    """Any attempt to open a connection fails the test."""

    def refuse(*args, **kwargs):
        raise AssertionError(f"network access attempted: {args[1:]}")

    monkeypatch.setattr(socket.socket, "connect", refuse)
    monkeypatch.setattr(socket.socket, "connect_ex", refuse)
    monkeypatch.setattr(socket, "create_connection", refuse)


# ------------------------------------------------------------------------------------------ sample data
def _write_ycb(data: Path) -> Path:
    ycb = data / "assets" / "mani_skill2_ycb"
    models = ycb / "models"
    box = trimesh.creation.box(BOX)
    (models / "003_cracker_box").mkdir(parents=True)
    box.export(models / "003_cracker_box" / "textured.obj")
    box.export(models / "003_cracker_box" / "collision.ply")
    apple = trimesh.creation.icosphere(subdivisions=2, radius=APPLE_R)
    apple.apply_translation([0.0, 0.0, 0.01])
    (models / "013_apple").mkdir(parents=True)
    apple.export(models / "013_apple" / "textured.obj")
    apple.export(models / "013_apple" / "collision.obj")  # the .obj alternative
    (models / "005_no_collision").mkdir(parents=True)
    box.export(models / "005_no_collision" / "textured.obj")
    h = np.asarray(BOX) / 2
    info = {
        "003_cracker_box": {"bbox": {"min": list(-h), "max": list(h)}, "scales": [1.0], "density": BOX_DENSITY},
        "013_apple": {"scales": [APPLE_SCALE]},  # no bbox: measured from the mesh
        "004_not_on_disk": {"bbox": {"min": [-0.1, -0.1, -0.1], "max": [0.1, 0.1, 0.1]}, "scales": [1.0]},
        "005_no_collision": {"bbox": {"min": list(-h), "max": list(h)}, "scales": [1.0]},
    }
    (ycb / "info_pick_v0.json").write_text(json.dumps(info))
    return ycb


def _box_obj(path: Path, extents, centre) -> None:
    m = trimesh.creation.box(extents)
    m.apply_translation(centre)
    m.export(path)


URDF = """<?xml version="1.0"?>
<robot name="tiny_cabinet">
  <link name="base">
    <visual><geometry><mesh filename="base.obj"/></geometry></visual>
    <collision><geometry><mesh filename="base.obj"/></geometry></collision>
  </link>
  <link name="link_drawer">
    <visual><geometry><mesh filename="drawer.obj"/></geometry></visual>
    <collision><geometry><mesh filename="drawer.obj"/></geometry></collision>
  </link>
  <link name="link_door">
    <visual name="door-1"><geometry><mesh filename="door.obj"/></geometry></visual>
    <visual name="handle-2"><origin xyz="-0.05 -0.7 0"/><geometry><box size="0.02 0.02 0.2"/></geometry></visual>
    <collision><geometry><mesh filename="door.obj"/></geometry></collision>
  </link>
  <joint name="joint_drawer" type="prismatic">
    <parent link="base"/><child link="link_drawer"/>
    <origin xyz="0 0 -0.3"/><axis xyz="-1 0 0"/>
    <limit lower="0" upper="0.4"/>
  </joint>
  <joint name="joint_door" type="revolute">
    <parent link="base"/><child link="link_door"/>
    <origin xyz="-0.3 0.4 0" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="0" upper="2.0"/>
  </joint>
</robot>
"""


def _write_pm(data: Path) -> Path:
    dataset = data / "partnet_mobility" / "dataset"
    model = dataset / PM_ID
    model.mkdir(parents=True)
    _box_obj(model / "base.obj", (0.6, 0.8, 1.0), (0, 0, 0))
    _box_obj(model / "drawer.obj", (0.5, 0.6, 0.2), (0, 0, 0))  # link frame at z=-0.3
    _box_obj(model / "door.obj", (0.02, 0.8, 1.0), (-0.01, -0.4, 0))  # hinge at the door's +y edge
    (model / "mobility_cvx.urdf").write_text(URDF)
    (model / "semantics.txt").write_text("link_drawer slider drawer\nlink_door hinge door\nbase free cabinet\n")
    (dataset / "12345").mkdir()  # a model folder without a URDF: skipped
    broken = dataset / "23456"  # URDF naming a mesh that is not there: skipped
    broken.mkdir()
    (broken / "mobility.urdf").write_text(URDF)
    meta = data / "partnet_mobility" / "meta"
    meta.mkdir(parents=True)
    (meta / "info_cabinet_door_train.json").write_text(
        json.dumps({PM_ID: {"num_target_links": 1, "partnet_mobility_id": int(PM_ID), "scale": PM_SCALE}}))
    return model


@pytest.fixture
def data(tmp_path) -> Path:
    d = tmp_path / "ms" / "data"
    _write_ycb(d)
    _write_pm(d)
    return d


# ------------------------------------------------------------------------------------------ YCB
def test_ycb_finds_exactly_the_models_on_disk(data):
    entries = ud.load_ycb(data)
    assert [e.id for e in entries] == ["ycb_003_cracker_box", "ycb_013_apple"]
    box, apple = entries
    assert box.kind == "rigid" and box.category == "cracker_box" and apple.category == "apple"
    assert box.source == "YCB via ManiSkill asset dir" and box.licence == "CC-BY-4.0 (YCB)"
    assert {"graspable", "food", "box"} <= set(box.tags)
    assert {"graspable", "fruit", "food"} <= set(apple.tags)
    assert Path(box.visual).is_absolute() and Path(box.visual).name == "textured.obj"
    assert Path(box.collision).name == "collision.ply" and Path(apple.collision).name == "collision.obj"
    assert all(Path(p).is_file() for e in entries for p in (e.visual, e.collision))


def test_ycb_sizes_offsets_and_mass(data):
    box, apple = ud.load_ycb(data)
    np.testing.assert_allclose(box.size_m, BOX, atol=1e-3)
    assert box.bbox_min_m[2] == pytest.approx(0.0, abs=1e-9)
    assert box.params["origin_dz_m"] == pytest.approx(BOX[2] / 2, abs=1e-9)
    assert box.params["file_scale"] == 1.0
    assert box.volume_m3 == pytest.approx(np.prod(BOX), rel=1e-6)
    assert box.mass_kg == pytest.approx(BOX_DENSITY * np.prod(BOX), rel=1e-6)

    mesh = trimesh.load(apple.collision, force="mesh")
    lo, hi = mesh.bounds * APPLE_SCALE
    np.testing.assert_allclose(apple.size_m, hi - lo, atol=1e-3)
    np.testing.assert_allclose(apple.size_m, [2 * APPLE_R * APPLE_SCALE] * 3, atol=1e-3)
    assert apple.params["origin_dz_m"] == pytest.approx(-lo[2], abs=1e-6)
    assert apple.bbox_min_m[2] == pytest.approx(0.0, abs=1e-9)
    assert apple.params["file_scale"] == APPLE_SCALE
    # default density 1000 (as ManiSkill), volume of the (scaled) hull
    assert apple.mass_kg == pytest.approx(1000 * mesh.convex_hull.volume * APPLE_SCALE**3, rel=1e-6)


def test_ycb_missing_files_are_skipped_with_a_debug_log(data, caplog):
    with caplog.at_level("DEBUG", logger=ud.__name__):
        ids = [e.id for e in ud.load_ycb(data)]
    assert "ycb_004_not_on_disk" not in ids and "ycb_005_no_collision" not in ids
    assert "004_not_on_disk" in caplog.text and "005_no_collision" in caplog.text


def test_ycb_without_info_json_reads_model_folders(data):
    (data / "assets" / "mani_skill2_ycb" / "info_pick_v0.json").unlink()
    entries = {e.id: e for e in ud.load_ycb(data)}
    assert set(entries) == {"ycb_003_cracker_box", "ycb_013_apple"}
    np.testing.assert_allclose(entries["ycb_003_cracker_box"].size_m, BOX, atol=1e-3)
    np.testing.assert_allclose(entries["ycb_013_apple"].size_m, [2 * APPLE_R] * 3, atol=1e-3)  # scale 1


@pytest.mark.parametrize("text, needle", [
    ("{not json", "cannot read JSON"),
    ("[1, 2]", "expected a JSON object"),
    (json.dumps({"003_cracker_box": {"bbox": {"min": [0, 0], "max": [1, 1, 1]}}}), "bbox.min"),
    (json.dumps({"003_cracker_box": {"scales": [-1]}}), "scales[0]"),
    (json.dumps({"003_cracker_box": "box"}), "expected an object"),
])
def test_malformed_info_json_raises_typed_error_naming_the_file(data, text, needle):
    info = data / "assets" / "mani_skill2_ycb" / "info_pick_v0.json"
    info.write_text(text)
    with pytest.raises(AssetNotFoundError) as exc:
        ud.load_ycb(data)
    assert str(info) in str(exc.value) and needle in str(exc.value)


def test_unreadable_collision_mesh_names_the_file(data):
    bad = data / "assets" / "mani_skill2_ycb" / "models" / "003_cracker_box" / "collision.ply"
    bad.write_bytes(b"ply\nthis is not a ply file\n")
    with pytest.raises(AssetNotFoundError, match="collision.ply"):
        ud.load_ycb(data)


def test_ycb_id_and_tags_helpers():
    assert ud.ycb_category("002_master_chef_can") == "master_chef_can"
    assert ud.ycb_category("065-a_cups") == "cups"
    assert common._asset_id("ycb", "065-a_cups") == "ycb_065_a_cups"
    assert "tool" in ud.ycb_tags("035_power_drill")
    assert "ball" in ud.ycb_tags("056_tennis_ball")
    assert {"kitchenware", "utensil"} <= set(ud.ycb_tags("031_spoon"))
    assert "graspable" not in ud.ycb_tags("029_plate")  # ManiSkill's PickSingleYCB leaves it out


# ------------------------------------------------------------------------------------------ PartNet-Mobility
def test_partnet_mobility_entry(data, caplog):
    with caplog.at_level("DEBUG", logger=ud.__name__):
        entries = ud.load_partnet_mobility(data)
    assert [e.id for e in entries] == [f"pm_{PM_ID}"]  # 12345 has no URDF, 23456 names missing meshes
    assert "12345" in caplog.text and "23456" in caplog.text
    e = entries[0]
    assert e.kind == "articulated" and e.fixed_base and e.category == "cabinet"
    assert e.licence == "PartNet-Mobility terms (non-commercial research)"
    assert {"articulated", "cabinet", "container", "door", "drawer"} <= set(e.tags)
    assert Path(e.urdf).is_absolute() and Path(e.urdf).name == "mobility_cvx.urdf"
    assert e.params["file_scale"] == PM_SCALE

    # bbox at the closed configuration, scaled: base 0.6 x 0.8 x 1.0 plus the 2 cm door in front (-x)
    np.testing.assert_allclose(e.bbox_min_m, [-0.32 * PM_SCALE, -0.4 * PM_SCALE, 0.0], atol=1e-6)
    np.testing.assert_allclose(e.bbox_max_m, [0.3 * PM_SCALE, 0.4 * PM_SCALE, 1.0 * PM_SCALE], atol=1e-6)
    assert e.params["origin_dz_m"] == pytest.approx(0.5 * PM_SCALE)

    # joints: semantics put the door first; limits from the URDF (prismatic scaled, revolute not)
    door, drawer = e.joints
    assert (door.name, door.type, door.handle_link) == ("joint_door", "revolute", "link_door")
    assert door.limits == pytest.approx((0.0, 2.0))
    assert door.closed_qpos == pytest.approx(0.0) and door.open_qpos == pytest.approx(0.8 * 2.0)
    assert door.handle_point_m == pytest.approx((-0.05 * PM_SCALE, -0.7 * PM_SCALE, 0.0))  # the "handle" visual
    assert (drawer.name, drawer.type, drawer.handle_link) == ("joint_drawer", "prismatic", "link_drawer")
    assert drawer.limits == pytest.approx((0.0, 0.4 * PM_SCALE))
    assert drawer.open_qpos == pytest.approx(0.8 * 0.4 * PM_SCALE)
    assert drawer.handle_point_m == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)  # collision bbox centre
    # moving parts at density 1000: door 0.02*0.8*1.0 + drawer 0.5*0.6*0.2 (m^3 at file scale)
    assert e.mass_kg == pytest.approx(1000 * (0.016 + 0.06) * PM_SCALE**3, rel=1e-6)


def test_partnet_mobility_without_metadata_and_with_metadata_bbox(data):
    e = ud.load_partnet_mobility(data, meta_files=[])[0]
    assert e.params["file_scale"] == 1.0 and e.category == "articulated_object"
    assert e.size_m == pytest.approx((0.62, 0.8, 1.0))
    meta = data / "partnet_mobility" / "meta" / "info_faucet_train.json"
    meta.write_text(json.dumps({PM_ID: {"scale": 0.2, "bbox": {"min": [-1, -1, -2], "max": [1, 1, 2]},
                                        "semantics": [["link_door", "hinge", "switch"]]}}))
    f = ud.load_partnet_mobility(data, meta_files=[meta])[0]
    assert f.category == "faucet" and "switch" in f.tags
    assert f.bbox_min_m == pytest.approx((-0.2, -0.2, 0.0)) and f.bbox_max_m == pytest.approx((0.2, 0.2, 0.8))
    assert f.params["origin_dz_m"] == pytest.approx(0.4)


def test_malformed_urdf_raises_typed_error_naming_the_file(data):
    urdf = data / "partnet_mobility" / "dataset" / PM_ID / "mobility_cvx.urdf"
    urdf.write_text("<robot><link name='a'></robot>")
    with pytest.raises(AssetNotFoundError, match="mobility_cvx.urdf"):
        ud.load_partnet_mobility(data)
    urdf.write_text(URDF.replace('upper="2.0"', 'upper="-2"'))
    with pytest.raises(AssetNotFoundError, match="joint_door"):
        ud.load_partnet_mobility(data)


def test_malformed_metadata_json_raises_typed_error_naming_the_file(data):
    meta = data / "partnet_mobility" / "meta" / "info_cabinet_door_train.json"
    meta.write_text(json.dumps({PM_ID: {"scale": "big"}}))
    with pytest.raises(AssetNotFoundError) as exc:
        ud.load_partnet_mobility(data)
    assert str(meta) in str(exc.value)


def test_shipped_maniskill_metadata_is_found():
    meta_dir = common._maniskill_package_meta_dir()
    assert meta_dir is not None and (meta_dir / "info_cabinet_door_train.json").is_file()
    meta = partnet_mobility._pm_metadata(sorted(meta_dir.glob("info_*.json")))
    assert meta["1000"].category == "cabinet" and meta["5000"].category == "faucet"


# ------------------------------------------------------------------------------------------ both, env var
def test_ms_asset_dir_is_honoured(data, monkeypatch):
    monkeypatch.setenv("MS_ASSET_DIR", str(data.parent))
    assert ud.maniskill_asset_dir() == data
    ids = [e.id for e in ud.user_dataset_entries()]
    assert ids == ["ycb_003_cracker_box", "ycb_013_apple", f"pm_{PM_ID}"]


def test_default_dir_and_nothing_there(tmp_path, monkeypatch):
    monkeypatch.delenv("MS_ASSET_DIR", raising=False)
    monkeypatch.setenv("HOME", str(tmp_path))
    assert ud.maniskill_asset_dir() == tmp_path / ".maniskill" / "data"
    assert ud.user_dataset_entries() == []
    assert not (tmp_path / ".maniskill").exists()  # nothing created
    monkeypatch.setenv("MS_ASSET_DIR", str(tmp_path / "empty"))
    (tmp_path / "empty" / "data").mkdir(parents=True)
    assert ud.user_dataset_entries() == []
    assert ud.load_ycb(tmp_path / "empty" / "data") == [] and ud.load_partnet_mobility(tmp_path / "nope") == []


def test_entries_round_trip_through_a_manifest(data, tmp_path):
    entries = ud.user_dataset_entries(data)
    path = tmp_path / "out" / "manifest.json"
    write_manifest(path, entries)
    back = read_manifest(path)
    assert sorted(back, key=lambda e: e.id) == sorted(entries, key=lambda e: e.id)
    assert all(isinstance(e, AssetEntry) for e in back)


# ------------------------------------------------------------------------------------------ SAPIEN
def test_paths_load_into_a_sapien_scene(data):
    import sapien

    box, apple = ud.load_ycb(data)
    scene = sapien.Scene()
    for e in (box, apple):
        s = [e.params["file_scale"]] * 3
        b = scene.create_actor_builder()
        b.add_multiple_convex_collisions_from_file(e.collision, pose=sapien.Pose(p=[0, 0, e.params["origin_dz_m"]]),
                                                   scale=s, density=e.mass_kg / e.volume_m3)
        b.add_visual_from_file(e.visual, scale=s)
        actor = b.build(e.id)
        body = actor.find_component_by_type(sapien.physx.PhysxRigidDynamicComponent)
        assert len(body.get_collision_shapes()) >= 1
        # PhysX hull cooking drops some of the sphere's vertices (137 of 162 here), so it comes out ~1.5% lighter
        assert body.mass == pytest.approx(e.mass_kg, rel=1e-3 if e is box else 0.05)

    pm = ud.load_partnet_mobility(data)[0]
    loader = scene.create_urdf_loader()
    loader.scale = pm.params["file_scale"]
    loader.load_multiple_collisions_from_file = True
    loader.fix_root_link = pm.fixed_base
    art = loader.load(pm.urdf)
    limits = {j.name: tuple(j.get_limits()[0]) for j in art.get_active_joints()}
    for j in pm.joints:
        assert limits[j.name] == pytest.approx(j.limits, abs=1e-6)
    assert not math.isnan(art.get_qpos().sum())
