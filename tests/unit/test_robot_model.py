"""The generated UR10e+ShadowHand URDF: structure, masses, and UR10e kinematics against the published DH table."""

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from gendex_envs.agents import robot_model as rm
from gendex_envs.agents.ur10e_shadow import ALL_JOINTS, CONTROL_JOINT_GROUPS, COUPLED_DISTAL, TIP_LINKS


@pytest.fixture(scope="module")
def urdf_root():
    return ET.parse(rm.robot_urdf_path()).getroot()


def test_urdf_has_thirty_named_revolute_joints(urdf_root):
    revolute = [j.get("name") for j in urdf_root.iter("joint") if j.get("type") == "revolute"]
    assert sorted(revolute) == sorted(ALL_JOINTS)
    assert len(revolute) == 30


def test_every_moving_link_has_mass_and_inertia(urdf_root):
    child_of_revolute = {j.find("child").get("link") for j in urdf_root.iter("joint") if j.get("type") == "revolute"}
    for link in urdf_root.iter("link"):
        if link.get("name") in child_of_revolute:
            mass = float(link.find("inertial/mass").get("value"))
            inertia = link.find("inertial/inertia")
            assert mass > 0, link.get("name")
            assert all(float(inertia.get(k)) > 0 for k in ("ixx", "iyy", "izz")), link.get("name")


def test_every_collision_shape_is_convex_primitive_or_mesh(urdf_root):
    kinds = {child.tag for geom in urdf_root.iter("collision") for child in geom.find("geometry")}
    assert kinds <= {"capsule", "box", "sphere", "cylinder", "mesh"}
    for link in urdf_root.iter("link"):
        if link.get("name") in TIP_LINKS:
            assert link.find("collision") is not None, f"{link.get('name')} needs a collision shape for contact"


def _dh(theta, d, a, alpha):
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1]])


@pytest.mark.parametrize("seed", range(3))
def test_ur10e_flange_matches_published_dh(seed):
    """Forward kinematics of the URDF (via SAPIEN's pinocchio model) equals the DH chain of the UR10e datasheet."""
    import sapien

    q = np.random.default_rng(seed).uniform(-np.pi, np.pi, 6)
    dh = [(rm.D1, 0, np.pi / 2), (0, rm.A2, 0), (0, rm.A3, 0), (rm.D4, 0, np.pi / 2), (rm.D5, 0, -np.pi / 2),
          (rm.D6, 0, 0)]
    expected = np.eye(4)
    for qi, (d, a, alpha) in zip(q, dh, strict=True):
        expected = expected @ _dh(qi, d, a, alpha)

    scene = sapien.Scene()
    loader = scene.create_urdf_loader()
    loader.fix_root_link = True
    robot = loader.load(str(rm.robot_urdf_path()))
    names = [j.name for j in robot.get_active_joints()]
    qpos = np.zeros(len(names))
    for i, joint in enumerate(("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint",
                               "wrist_2_joint", "wrist_3_joint")):
        qpos[names.index(joint)] = q[i]
    model = robot.create_pinocchio_model()
    model.compute_forward_kinematics(qpos)
    links = [link.name for link in robot.get_links()]
    flange = model.get_link_pose(links.index("tool0")).to_transformation_matrix()
    np.testing.assert_allclose(flange[:3, 3], expected[:3, 3], atol=1e-6)
    np.testing.assert_allclose(flange[:3, :3], expected[:3, :3], atol=1e-6)


def test_control_groups_are_documented_subsets():
    assert set(CONTROL_JOINT_GROUPS) == {"arm", "hand", "both", "three_finger", "arm_two_finger", "lift_inspire"}
    for mode, joints in CONTROL_JOINT_GROUPS.items():
        assert set(joints) <= set(ALL_JOINTS), mode
    assert len(CONTROL_JOINT_GROUPS["both"]) - len(COUPLED_DISTAL) == 26  # 6 arm + 20 actuated hand joints


def test_cache_is_reused(tmp_path, monkeypatch):
    monkeypatch.setenv("GENDEX_CACHE", str(tmp_path))
    first = rm.robot_urdf_path()
    mtime = first.stat().st_mtime_ns
    assert rm.robot_urdf_path() == first and first.stat().st_mtime_ns == mtime
    assert not list(first.parent.parent.glob(".building-*")), "temporary build folder left behind"
    assert (first.parent / "SHADOW_HAND_LICENSE.md").is_file()
