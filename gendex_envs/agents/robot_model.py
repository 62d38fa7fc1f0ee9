"""Build the UR10e + ShadowHand URDF from sources that are on this machine, and cache it.

* **UR10e** — written here from Universal Robots' published DH parameters and link masses. Geometry is primitive
  (capsules and cylinders): every collision shape is convex, so a motion planner can use it as is.
* **ShadowHand** — the OpenAI/Shadow MJCF shipped in ``gymnasium-robotics`` (Apache-2.0, see its ``LICENSE.md``).
  It is compiled with MuJoCo, which resolves the include files and defaults and computes each body's mass and
  inertia; bodies, hinge joints, collision primitives and visual meshes are then written out as URDF. Meshes are
  exported from the *compiled* model (MuJoCo re-centres mesh geoms on their centroid, so the source STL files would
  sit in the wrong place).

The result lives in a cache folder keyed by the builder version and the source package versions, written to a
temporary folder and renamed into place, so concurrent first uses never see half a robot. Nothing is downloaded.
"""

from __future__ import annotations

import hashlib
import logging
import os
import shutil
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from gendex_envs.atomic_io import atomic_dir

log = logging.getLogger(__name__)

BUILDER_VERSION = "4"
"""Bump when the generated URDF changes, so stale caches are rebuilt."""

HAND_PREFIX = "robot0:"
"""Name prefix of the ShadowHand bodies/joints in the gymnasium-robotics MJCF; stripped in the URDF."""

HAND_ROOT_BODY = "robot0:forearm"
"""First MJCF body mounted on the UR10e flange (the hand's forearm, which carries the two wrist joints)."""


@dataclass(frozen=True)
class URLink:
    """One UR10e link: the joint that drives it and the shapes it carries (all in the link frame)."""

    name: str
    joint: str
    origin_xyz: tuple[float, float, float]
    """Translation from the parent link frame to this joint (DH a, 0, d of the previous row)."""
    origin_rpy: tuple[float, float, float]
    """Rotation (DH alpha of the previous row, as roll)."""
    mass_kg: float
    capsules: tuple[tuple[tuple[float, float, float], tuple[float, float, float], float], ...]
    """(start, end, radius) capsules approximating the link's housing and tube."""
    limit_rad: float = 2 * np.pi
    effort_nm: float = 330.0
    velocity_rad_s: float = 2.094


# UR10e DH (Universal Robots, "DH parameters for calculations of kinematics and dynamics"):
#   d1 0.1807, a2 -0.6127, a3 -0.57155, d4 0.17415, d5 0.11985, d6 0.11655, alpha (pi/2, 0, 0, pi/2, -pi/2, 0).
# Masses (kg): 7.369, 13.051, 3.989, 2.1, 1.98, 0.615. Each joint rotates about the z axis of its link frame; the
# fixed transform to the next joint is Trans(a, 0, d) * RotX(alpha) of the DH row, which is exactly a URDF origin.
D1, A2, A3, D4, D5, D6 = 0.1807, -0.6127, -0.57155, 0.17415, 0.11985, 0.11655
HALF_PI = np.pi / 2
UR10E_LINKS: tuple[URLink, ...] = (
    URLink("shoulder_link", "shoulder_pan_joint", (0, 0, 0), (0, 0, 0), 7.369,
           (((0, 0, 0.115), (0, 0, D1 - 0.04), 0.075), ((0, -0.09, D1), (0, 0.09, D1), 0.078))),
    URLink("upper_arm_link", "shoulder_lift_joint", (0, 0, D1), (HALF_PI, 0, 0), 13.051,
           (((0, 0, 0.0), (A2, 0, 0), 0.062), ((A2, 0, -0.07), (A2, 0, 0.07), 0.07))),
    URLink("forearm_link", "elbow_joint", (A2, 0, 0), (0, 0, 0), 3.989,
           (((0, 0, 0), (A3, 0, 0), 0.046), ((A3, 0, -0.06), (A3, 0, 0.06), 0.05)), limit_rad=np.pi, effort_nm=150.0),
    URLink("wrist_1_link", "wrist_1_joint", (A3, 0, 0), (0, 0, 0), 2.1,
           (((0, 0, 0.0), (0, 0, D4 - 0.05), 0.046),), effort_nm=56.0, velocity_rad_s=3.14),
    URLink("wrist_2_link", "wrist_2_joint", (0, 0, D4), (HALF_PI, 0, 0), 1.98,
           (((0, 0, 0.0), (0, 0, D5 - 0.05), 0.046),), effort_nm=56.0, velocity_rad_s=3.14),
    URLink("wrist_3_link", "wrist_3_joint", (0, 0, D5), (-HALF_PI, 0, 0), 0.615,
           (((0, 0, -0.02), (0, 0, D6 - 0.03), 0.045),), effort_nm=56.0, velocity_rad_s=3.14),
)
UR10E_FLANGE_OFFSET_M = D6
"""Distance from the wrist_3 joint frame to the tool flange along its z axis."""

ARM_BASE_RADIUS_M = 0.095
ARM_BASE_HEIGHT_M = 0.04


def _fmt(v) -> str:
    return " ".join(f"{float(x):.9g}" for x in np.asarray(v).ravel())


def quat_wxyz_to_rpy(q) -> np.ndarray:
    """(4,) unit quaternion (w, x, y, z) -> (3,) URDF roll, pitch, yaw (fixed-axis XYZ), radians."""
    w, x, y, z = np.asarray(q, dtype=np.float64) / np.linalg.norm(q)
    roll = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2 * (w * y - z * x), -1.0, 1.0))
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return np.array([roll, pitch, yaw])


def segment_frame(p0, p1) -> tuple[np.ndarray, np.ndarray, float]:
    """Frame whose z axis runs from p0 to p1: returns (centre (3,), rpy (3,), length)."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    d = p1 - p0
    length = float(np.linalg.norm(d))
    z = d / length
    # shortest rotation taking (0, 0, 1) to z, as a quaternion
    c = float(z[2])
    if c < -1 + 1e-9:
        q = np.array([0.0, 1.0, 0.0, 0.0])
    else:
        axis = np.cross([0.0, 0.0, 1.0], z)
        q = np.array([1.0 + c, *axis])
        q /= np.linalg.norm(q)
    return (p0 + p1) / 2, quat_wxyz_to_rpy(q), length


def _capsule_xml(p0, p1, radius: float, tag: str, rgba: str | None = None) -> str:
    centre, rpy, length = segment_frame(p0, p1)
    mat = f'<material name="ur_grey"><color rgba="{rgba}"/></material>' if rgba else ""
    return (
        f'<{tag}><origin xyz="{_fmt(centre)}" rpy="{_fmt(rpy)}"/>'
        f'<geometry><capsule radius="{radius:.6g}" length="{length:.6g}"/></geometry>{mat}</{tag}>'
    )


def _capsule_inertia(mass: float, capsules) -> tuple[np.ndarray, np.ndarray]:
    """Rough inertia of a link: mass spread over its capsules as solid rods. Returns (com (3,), diag inertia (3,))."""
    pts = np.array([np.add(a, b) / 2 for a, b, _ in capsules])
    com = pts.mean(axis=0)
    extent = np.ptp(np.array([p for a, b, _ in capsules for p in (a, b)]), axis=0) + 2 * max(r for *_, r in capsules)
    ex, ey, ez = extent
    inertia = mass / 12.0 * np.array([ey**2 + ez**2, ex**2 + ez**2, ex**2 + ey**2])
    return com, inertia


def ur10e_urdf_links(arm_rgba: str = "0.72 0.74 0.78 1") -> tuple[list[str], list[str]]:
    """URDF <link>/<joint> elements of the UR10e (base_link .. tool0). Returns (links, joints)."""
    links = [
        '<link name="base_link"><inertial><origin xyz="0 0 0.02"/><mass value="4.0"/>'
        '<inertia ixx="0.0061" iyy="0.0061" izz="0.0112" ixy="0" ixz="0" iyz="0"/></inertial>'
        f'<visual><origin xyz="0 0 {ARM_BASE_HEIGHT_M / 2}"/><geometry><cylinder radius="{ARM_BASE_RADIUS_M}" '
        f'length="{ARM_BASE_HEIGHT_M}"/></geometry><material name="ur_dark"><color rgba="0.2 0.22 0.25 1"/>'
        f'</material></visual><collision><origin xyz="0 0 {ARM_BASE_HEIGHT_M / 2}"/><geometry><cylinder '
        f'radius="{ARM_BASE_RADIUS_M}" length="{ARM_BASE_HEIGHT_M}"/></geometry></collision></link>'
    ]
    joints = []
    parent = "base_link"
    for link in UR10E_LINKS:
        com, inertia = _capsule_inertia(link.mass_kg, link.capsules)
        shapes = "".join(
            _capsule_xml(a, b, r, "visual", arm_rgba) + _capsule_xml(a, b, r, "collision") for a, b, r in link.capsules
        )
        links.append(
            f'<link name="{link.name}"><inertial><origin xyz="{_fmt(com)}"/><mass value="{link.mass_kg}"/>'
            f'<inertia ixx="{inertia[0]:.6g}" iyy="{inertia[1]:.6g}" izz="{inertia[2]:.6g}" ixy="0" ixz="0" iyz="0"/>'
            f"</inertial>{shapes}</link>"
        )
        joints.append(
            f'<joint name="{link.joint}" type="revolute"><parent link="{parent}"/><child link="{link.name}"/>'
            f'<origin xyz="{_fmt(link.origin_xyz)}" rpy="{_fmt(link.origin_rpy)}"/><axis xyz="0 0 1"/>'
            f'<limit lower="{-link.limit_rad:.6f}" upper="{link.limit_rad:.6f}" effort="{link.effort_nm}" '
            f'velocity="{link.velocity_rad_s}"/></joint>'
        )
        parent = link.name
    links.append('<link name="tool0"/>')
    joints.append(
        f'<joint name="flange_fixed_joint" type="fixed"><parent link="{parent}"/><child link="tool0"/>'
        f'<origin xyz="0 0 {UR10E_FLANGE_OFFSET_M}"/></joint>'
    )
    return links, joints


def shadow_hand_mjcf_path() -> Path:
    """The ShadowHand scene MJCF shipped by gymnasium-robotics (includes robot.xml, shared.xml, meshes)."""
    import gymnasium_robotics

    return Path(gymnasium_robotics.__file__).parent / "envs" / "assets" / "hand" / "reach.xml"


def _mj_name(model, kind: str, idx: int) -> str:
    return getattr(model, kind)(idx).name


def _strip(name: str) -> str:
    return name[len(HAND_PREFIX):] if name.startswith(HAND_PREFIX) else name


def shadow_hand_urdf_links(mesh_dir: Path) -> tuple[list[str], list[str]]:
    """URDF <link>/<joint> elements of the ShadowHand, rooted at ``forearm`` (parent ``tool0`` is added by the caller).

    Writes the compiled visual/collision meshes as OBJ files into ``mesh_dir``.
    """
    import mujoco

    model = mujoco.MjModel.from_xml_path(str(shadow_hand_mjcf_path()))
    root = model.body(HAND_ROOT_BODY).id
    bodies = [root]
    for b in range(model.nbody):  # bodies are stored parents-first
        if b != root and model.body_parentid[b] in bodies:
            bodies.append(b)

    written_meshes: dict[int, str] = {}

    def mesh_file(mesh_id: int) -> str:
        if mesh_id not in written_meshes:
            name = _strip(_mj_name(model, "mesh", mesh_id)).replace(":", "_") + ".obj"
            v0, nv = model.mesh_vertadr[mesh_id], model.mesh_vertnum[mesh_id]
            f0, nf = model.mesh_faceadr[mesh_id], model.mesh_facenum[mesh_id]
            verts = model.mesh_vert[v0:v0 + nv]
            faces = model.mesh_face[f0:f0 + nf] + 1
            lines = [f"v {x:.7g} {y:.7g} {z:.7g}" for x, y, z in verts] + [f"f {a} {b} {c}" for a, b, c in faces]
            (mesh_dir / name).write_text("\n".join(lines) + "\n")
            written_meshes[mesh_id] = name
        return written_meshes[mesh_id]

    links, joints = [], []
    for b in bodies:
        name = _strip(model.body(b).name)
        rpy_i = quat_wxyz_to_rpy(model.body_iquat[b])
        ixx, iyy, izz = model.body_inertia[b]
        parts = [
            f'<inertial><origin xyz="{_fmt(model.body_ipos[b])}" rpy="{_fmt(rpy_i)}"/>'
            f'<mass value="{model.body_mass[b]:.6g}"/><inertia ixx="{ixx:.6g}" iyy="{iyy:.6g}" izz="{izz:.6g}" '
            f'ixy="0" ixz="0" iyz="0"/></inertial>'
        ]
        for g in np.flatnonzero(model.geom_bodyid == b):
            origin = f'<origin xyz="{_fmt(model.geom_pos[g])}" rpy="{_fmt(quat_wxyz_to_rpy(model.geom_quat[g]))}"/>'
            gtype, size = model.geom_type[g], model.geom_size[g]
            if gtype == mujoco.mjtGeom.mjGEOM_MESH:
                geom = f'<mesh filename={quoteattr(mesh_file(model.geom_dataid[g]))}/>'
            elif gtype == mujoco.mjtGeom.mjGEOM_CAPSULE:
                geom = f'<capsule radius="{size[0]:.6g}" length="{2 * size[1]:.6g}"/>'
            elif gtype == mujoco.mjtGeom.mjGEOM_BOX:
                geom = f'<box size="{_fmt(2 * size)}"/>'
            elif gtype == mujoco.mjtGeom.mjGEOM_SPHERE:
                geom = f'<sphere radius="{size[0]:.6g}"/>'
            else:
                raise NotImplementedError(f"ShadowHand geom type {gtype} of {model.geom(g).name}")
            is_collision = model.geom_contype[g] != 0 or model.geom_conaffinity[g] != 0
            if is_collision:
                parts.append(f"<collision>{origin}<geometry>{geom}</geometry></collision>")
            elif model.geom_group[g] == 1:
                mat = model.geom_matid[g]
                rgba = model.mat_rgba[mat] if mat >= 0 else model.geom_rgba[g]
                parts.append(
                    f'<visual>{origin}<geometry>{geom}</geometry><material name="shadow_{name}_{g}">'
                    f'<color rgba="{_fmt(rgba)}"/></material></visual>'
                )
        links.append(f'<link name="{name}">{"".join(parts)}</link>')

        if b == root:
            continue
        parent = _strip(model.body(model.body_parentid[b]).name)
        jids = np.flatnonzero(model.jnt_bodyid == b)
        if len(jids) > 1:
            raise NotImplementedError(f"body {name} has {len(jids)} joints")
        origin = f'<origin xyz="{_fmt(model.body_pos[b])}" rpy="{_fmt(quat_wxyz_to_rpy(model.body_quat[b]))}"/>'
        if len(jids) == 0:
            joints.append(f'<joint name="{name}_fixed" type="fixed"><parent link="{parent}"/><child link="{name}"/>'
                          f"{origin}</joint>")
            continue
        j = jids[0]
        if np.any(np.abs(model.jnt_pos[j]) > 1e-9):
            raise NotImplementedError(f"joint {model.jnt(j).name} is offset from its body origin")
        lo, hi = model.jnt_range[j]
        dof = model.jnt_dofadr[j]
        joints.append(
            f'<joint name="{_strip(model.jnt(j).name)}" type="revolute"><parent link="{parent}"/>'
            f'<child link="{name}"/>{origin}<axis xyz="{_fmt(model.jnt_axis[j])}"/>'
            f'<limit lower="{lo:.6f}" upper="{hi:.6f}" effort="5" velocity="6"/>'
            f'<dynamics damping="{model.dof_damping[dof]:.6g}" friction="0"/></joint>'
        )
    return links, joints


HAND_MOUNT_RPY = (0.0, 0.0, 0.0)
"""Rotation of the hand's forearm frame relative to the UR10e tool flange (forearm z = flange z, out of the arm)."""


def build_urdf_text(mesh_dir: Path) -> str:
    ur_links, ur_joints = ur10e_urdf_links()
    hand_links, hand_joints = shadow_hand_urdf_links(mesh_dir)
    mount = (
        f'<joint name="hand_mount_joint" type="fixed"><parent link="tool0"/><child link="{_strip(HAND_ROOT_BODY)}"/>'
        f'<origin xyz="0 0 0" rpy="{_fmt(HAND_MOUNT_RPY)}"/></joint>'
    )
    body = "\n".join([*ur_links, *hand_links, *ur_joints, mount, *hand_joints])
    return f'<?xml version="1.0"?>\n<robot name="ur10e_shadow">\n{body}\n</robot>\n'


def cache_root() -> Path:
    """Folder for generated artefacts: ``$GENDEX_CACHE`` or ``~/.cache/gendex``."""
    return Path(os.environ.get("GENDEX_CACHE", Path.home() / ".cache" / "gendex"))


def _source_key() -> str:
    from importlib.metadata import version

    text = f"{BUILDER_VERSION}|{version('mujoco')}|{version('gymnasium-robotics')}|{Path(__file__).read_bytes()!r}"
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def robot_urdf_path() -> Path:
    """Path of the cached UR10e+ShadowHand URDF, building it on first use (atomic: temp folder, then rename)."""
    target = cache_root() / "robots" / f"ur10e_shadow-{_source_key()}"
    urdf = target / "ur10e_shadow.urdf"
    if urdf.is_file():
        return urdf
    try:
        with atomic_dir(target) as tmp:
            (tmp / "ur10e_shadow.urdf").write_text(build_urdf_text(tmp))
            # the MJCF's header: "LICENSE.md must be kept together with this file"
            shutil.copy(shadow_hand_mjcf_path().parent.parent / "LICENSE.md", tmp / "SHADOW_HAND_LICENSE.md")
        log.info("built robot model %s", target)
    except FileExistsError:  # another process won the race; its copy is identical
        pass
    return urdf
