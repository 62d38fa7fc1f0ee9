"""``UR10eShadowHand``: a ShadowHand (24 DoF) on a UR10e arm (6 DoF), as a ManiSkill agent.

Degrees of freedom (30 joints, 26 actuated):

=========  ============================================================================================
group      joints (articulation order may differ; use the names)
=========  ============================================================================================
arm (6)    shoulder_pan, shoulder_lift, elbow, wrist_1, wrist_2, wrist_3 (``*_joint``)
wrist (2)  WRJ1 (radial/ulnar), WRJ0 (flexion)
ff (4)     FFJ3 (abduction), FFJ2, FFJ1, FFJ0 (flexion; FFJ0 follows FFJ1)
mf (4)     MFJ3, MFJ2, MFJ1, MFJ0 (MFJ0 follows MFJ1)
rf (4)     RFJ3, RFJ2, RFJ1, RFJ0 (RFJ0 follows RFJ1)
lf (5)     LFJ4 (metacarpal cup), LFJ3, LFJ2, LFJ1, LFJ0 (LFJ0 follows LFJ1)
th (5)     THJ4 (rotation), THJ3, THJ2, THJ1, THJ0
=========  ============================================================================================

The distal joints J0 of the four fingers are coupled to J1 by tendons in the real hand (and in MuJoCo); PhysX
does not import that coupling, so the controller does it: an action never addresses a J0 joint, whose target is
always its J1's. The robot's links ignore gravity (a gravity-compensated controller) and do not collide with each
other; they collide with everything else.

``control_joint`` picks which joints an action drives; every other joint is frozen at its current target.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import sapien
import torch
from mani_skill.agents.base_agent import BaseAgent, Keyframe
from mani_skill.agents.registration import register_agent
from mani_skill.utils.structs import Actor, Articulation, Link

from gendex_envs.agents.contacts import ContactTable
from gendex_envs.agents.controller import FreezingJointPosControllerConfig
from gendex_envs.agents.robot_model import robot_urdf_path
from gendex_envs.errors import ControlModeError
from gendex_envs.geometry import quat_rotate
from gendex_envs.physx import px_objects

log = logging.getLogger(__name__)

ARM_JOINTS = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
              "wrist_3_joint")
WRIST_JOINTS = ("WRJ1", "WRJ0")
FINGER_JOINTS = {
    "th": ("THJ4", "THJ3", "THJ2", "THJ1", "THJ0"),
    "ff": ("FFJ3", "FFJ2", "FFJ1", "FFJ0"),
    "mf": ("MFJ3", "MFJ2", "MFJ1", "MFJ0"),
    "rf": ("RFJ3", "RFJ2", "RFJ1", "RFJ0"),
    "lf": ("LFJ4", "LFJ3", "LFJ2", "LFJ1", "LFJ0"),
}
HAND_JOINTS = WRIST_JOINTS + tuple(j for f in FINGER_JOINTS.values() for j in f)
ALL_JOINTS = ARM_JOINTS + HAND_JOINTS
COUPLED_DISTAL = {"FFJ0": "FFJ1", "MFJ0": "MFJ1", "RFJ0": "RFJ1", "LFJ0": "LFJ1"}
"""Follower distal joint -> leader middle joint."""

_fingers = lambda *names: tuple(j for n in names for j in FINGER_JOINTS[n])  # noqa: E731
CONTROL_JOINT_GROUPS: dict[str, tuple[str, ...]] = {
    "arm": ARM_JOINTS,
    "hand": HAND_JOINTS,
    "both": ALL_JOINTS,
    "three_finger": _fingers("th", "ff", "mf"),
    "arm_two_finger": ARM_JOINTS + _fingers("th", "mf"),
    "lift_inspire": ("wrist_1_joint",) + _fingers("th", "ff", "mf", "rf", "lf"),
}
"""``control_joint`` mode -> joints the action drives (coupled distal joints are never in the action)."""

TIP_LINKS = ("thdistal", "ffdistal", "mfdistal", "rfdistal", "lfdistal")
"""Fingertip links, in the order of every ``[N, 5, ...]`` fingertip tensor: thumb, index, middle, ring, little."""
TIP_OFFSETS_M = (0.0275, 0.026, 0.026, 0.026, 0.026)
"""Distance of each fingertip point along its distal link's z axis (the MJCF's ``S_*tip`` sites)."""
PALM_LINK = "palm"
HAND_GROUP_LINKS: dict[str, tuple[str, ...]] = {
    "th": ("thbase", "thproximal", "thhub", "thmiddle", "thdistal"),
    "ff": ("ffknuckle", "ffproximal", "ffmiddle", "ffdistal"),
    "mf": ("mfknuckle", "mfproximal", "mfmiddle", "mfdistal"),
    "rf": ("rfknuckle", "rfproximal", "rfmiddle", "rfdistal"),
    "lf": ("lfmetacarpal", "lfknuckle", "lfproximal", "lfmiddle", "lfdistal"),
    "palm": ("palm",),
}
"""Link groups of :meth:`UR10eShadowHand.get_hand_group_obj_mean_force`, in its output order."""

SELF_COLLISION_BIT = 1 << 29
"""Bit set in collision_groups[2] of every robot shape. PhysX (SAPIEN's filter) ignores a pair whose groups[3] are
equal and whose groups[2] share a bit; ManiSkill uses groups[3] for the sub-scene index, so it is left alone."""


@dataclass(frozen=True)
class DriveGains:
    stiffness: float
    damping: float
    force_limit: float


ARM_GAINS = DriveGains(stiffness=4000.0, damping=400.0, force_limit=330.0)
WRIST_GAINS = DriveGains(stiffness=300.0, damping=10.0, force_limit=30.0)
"""Stiff enough that arm accelerations barely swing a frozen wrist (measured <= 0.003 rad under random arm motion)."""
FINGER_GAINS = DriveGains(stiffness=15.0, damping=0.5, force_limit=2.0)
"""Finger PD gains that grasp reliably in PhysX at 120 Hz (stiffness 10-20, damping ~0.5, force 1-5 N·m)."""

DELTA_LIMIT_RAD = {"arm": 0.05, "hand": 0.1}
"""Per-control-step bound of ``pd_joint_delta_pos`` actions, for arm and hand joints."""


def free_joints(control_joint: str) -> list[str]:
    """Joints the actions of ``control_joint`` mode drive (its group without the coupled distal joints)."""
    return [j for j in CONTROL_JOINT_GROUPS[control_joint] if j not in COUPLED_DISTAL]


def delta_limits(joints: list[str]) -> list[float]:
    """Per-control-step bound (rad) of a ``pd_joint_delta_pos`` action on each of ``joints``."""
    return [DELTA_LIMIT_RAD["arm" if j in ARM_JOINTS else "hand"] for j in joints]

# Keyframes, by joint name (coupled distal joints equal their leader).
_REST_ARM = (2.683, -1.71, 2.408, -0.699, 1.112, 0.0)
"""Elbow and wrist up, palm facing the table 0.30 m above it 0.80 m in front of the base, fingers pointing away from
the base (found by IK). The wrist-up branch keeps the UR wrist links above the hand when it reaches down to the table;
the wrist-down branch drives them into the table top."""
_OPEN_HAND = {j: 0.0 for j in HAND_JOINTS}
_RELAXED_HAND = _OPEN_HAND | {"FFJ2": 0.3, "FFJ1": 0.3, "FFJ0": 0.3, "MFJ2": 0.3, "MFJ1": 0.3, "MFJ0": 0.3,
                              "RFJ2": 0.3, "RFJ1": 0.3, "RFJ0": 0.3, "LFJ2": 0.3, "LFJ1": 0.3, "LFJ0": 0.3,
                              "THJ4": 0.6, "THJ3": 0.3}
_PALM_UP_ARM = _REST_ARM[:5] + (-3.1416,)
"""The rest arm with wrist_3 turned half a turn about the forearm axis (IK finds exactly this for the target): palm
facing straight up 0.30 m above the table at x = 0, fingers pointing away from the base, thumb towards -y. The UR
links stay where they are at rest, above the hand and clear of the table."""
_CUPPED_HAND = _OPEN_HAND | {"FFJ2": 0.25, "FFJ1": 0.2, "FFJ0": 0.2, "MFJ2": 0.25, "MFJ1": 0.2, "MFJ0": 0.2,
                            "RFJ2": 0.25, "RFJ1": 0.2, "RFJ0": 0.2, "LFJ4": 0.3, "LFJ2": 0.25, "LFJ1": 0.2,
                            "LFJ0": 0.2, "THJ4": 1.0, "THJ3": 0.2}
"""Fingers a little flexed, little-finger metacarpal cupped and thumb abducted: a shallow bowl a ball rests in."""
KEYFRAME_QPOS_BY_NAME: dict[str, dict[str, float]] = {
    "rest": dict(zip(ARM_JOINTS, _REST_ARM, strict=True)) | _RELAXED_HAND,
    "pregrasp_open": dict(zip(ARM_JOINTS, _REST_ARM, strict=True)) | _OPEN_HAND | {"THJ4": 1.0, "THJ3": 0.2},
    "palm_up": dict(zip(ARM_JOINTS, _PALM_UP_ARM, strict=True)) | _CUPPED_HAND,
}


@register_agent()
class UR10eShadowHand(BaseAgent):
    """ShadowHand on a UR10e; see the module docstring for the DoF table and control modes."""

    uid = "ur10e_shadow"
    fix_root_link = True
    disable_self_collisions = True

    def __init__(self, *args, control_joint: str = "both", **kwargs):
        if control_joint not in CONTROL_JOINT_GROUPS:
            raise ControlModeError(
                f"control_joint={control_joint!r} is not a mode; allowed: {sorted(CONTROL_JOINT_GROUPS)}"
            )
        self.control_joint = control_joint
        """Which joints actions drive: one of :data:`CONTROL_JOINT_GROUPS`."""
        super().__init__(*args, **kwargs)

    @property
    def urdf_path(self) -> str:  # built (once, cached) from in-repo UR10e data + the gymnasium-robotics ShadowHand
        return str(robot_urdf_path())

    @property
    def keyframes(self) -> dict[str, Keyframe]:
        return {
            name: Keyframe(pose=sapien.Pose(), qpos=self.qpos_from_names(q))
            for name, q in KEYFRAME_QPOS_BY_NAME.items()
        }

    def qpos_from_names(self, by_name: dict[str, float]) -> np.ndarray:
        """Joint positions by name -> (30,) array in the articulation's active-joint order."""
        order = [j.name for j in self.robot.get_active_joints()]
        return np.array([by_name[n] for n in order], dtype=np.float32)

    def set_action(self, action):
        if isinstance(action, torch.Tensor) and not self.scene.gpu_sim_enabled:
            # ManiSkill's NaN check goes through numpy's array protocol (about 5 us); the tensor's own is cheaper
            if torch.isnan(action).any():
                raise ValueError("Action cannot be NaN. Environment received:", action)
            self.controller.set_action(action)
            return
        super().set_action(action)

    # ------------------------------------------------------------------ loading
    def _after_loading_articulation(self):
        for link in self.robot.get_links():
            for obj in px_objects(link):
                obj.disable_gravity = True
                for shape in obj.collision_shapes:
                    groups = shape.get_collision_groups()
                    groups[2] |= SELF_COLLISION_BIT
                    shape.set_collision_groups(groups)
        self.tip_links: list[Link] = [self.robot.links_map[n] for n in TIP_LINKS]
        """The five distal links (th, ff, mf, rf, lf)."""
        self.palm_link: Link = self.robot.links_map[PALM_LINK]
        self.group_links: dict[str, list[Link]] = {
            g: [self.robot.links_map[n] for n in names] for g, names in HAND_GROUP_LINKS.items()
        }
        self._tip_offsets = torch.tensor(TIP_OFFSETS_M, dtype=torch.float32, device=self.device)
        self._tip_offsets_np = np.asarray(TIP_OFFSETS_M, dtype=np.float32)
        self._px_tip_links = [px_objects(link)[0] for link in self.tip_links]
        self._group_link_list = [link for links in self.group_links.values() for link in links]
        self._group_index = torch.tensor([g for g, links in enumerate(self.group_links.values()) for _ in links],
                                         device=self.device)
        self._group_sizes = torch.tensor([len(links) for links in self.group_links.values()], dtype=torch.float32,
                                         device=self.device)
        self.contacts = ContactTable(self.scene, self.robot.get_links())
        """Contact impulses, one pass per physics step; the env must ``contacts.invalidate()`` after stepping."""

    @property
    def _controller_configs(self):
        order = [j.name for j in self.robot.get_active_joints()]
        free = free_joints(self.control_joint)

        def gains(attr: str) -> list[float]:
            return [getattr(ARM_GAINS if j in ARM_JOINTS else WRIST_GAINS if j in WRIST_JOINTS else FINGER_GAINS,
                            attr) for j in order]

        common = dict(joint_names=order, stiffness=gains("stiffness"), damping=gains("damping"),
                      force_limit=gains("force_limit"), free_joint_names=free, mimic=dict(COUPLED_DISTAL))
        free_delta = delta_limits(free)
        return dict(
            pd_joint_pos=FreezingJointPosControllerConfig(lower=None, upper=None, normalize_action=False, **common),
            pd_joint_delta_pos=FreezingJointPosControllerConfig(
                lower=[-d for d in free_delta], upper=free_delta, use_delta=True, use_target=True,
                normalize_action=True, **common),
        )

    # ------------------------------------------------------------------ reward-code API (batched)
    @property
    def tip_poses(self) -> torch.Tensor:
        """[N, 5*7] fingertip poses (x, y, z, qw, qx, qy, qz) of th, ff, mf, rf, lf, concatenated."""
        if self.scene.gpu_sim_enabled:
            poses = torch.stack([link.pose.raw_pose for link in self.tip_links], dim=1)  # [N, 5, 7]
            offsets = torch.zeros(poses.shape[:2] + (3,), device=self.device)
            offsets[..., 2] = self._tip_offsets
            tips = poses[..., :3] + quat_rotate(poses[..., 3:], offsets)
            return torch.cat([tips, poses[..., 3:]], dim=-1).flatten(1)
        # CPU, one env: read the five link poses from PhysX and offset them along their z axes in numpy
        rows = np.empty((5, 7), dtype=np.float32)
        for row, link in zip(rows, self._px_tip_links, strict=True):
            pose = link.entity_pose
            row[:3], row[3:] = pose.p, pose.q
        w, x, y, z = rows[:, 3], rows[:, 4], rows[:, 5], rows[:, 6]
        z_axis = np.stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)], axis=1)
        rows[:, :3] += z_axis * self._tip_offsets_np[:, None]
        return torch.from_numpy(rows.reshape(1, 35)).to(self.device)

    @property
    def tip_positions(self) -> torch.Tensor:
        """[N, 5, 3] fingertip positions (th, ff, mf, rf, lf), metres."""
        return self.tip_poses.view(-1, 5, 7)[..., :3]

    def _contact_forces(self, links: list[Link], obj: Actor | Link | Articulation | None) -> torch.Tensor:
        """[N, len(links), 3] net (obj None) or pairwise contact forces on each link, newtons.

        ``obj`` may be an articulation: forces from all its links are summed.
        """
        if obj is None:
            impulses = self.contacts.net_impulses(links)
        else:
            others = obj.get_links() if isinstance(obj, Articulation) else [obj]
            impulses = self.contacts.pair_impulses(links, others)
        return impulses / self.scene.timestep

    def get_fsr_force(self) -> torch.Tensor:
        """[N, 5, 3] net contact force on each fingertip link (th, ff, mf, rf, lf), N."""
        return self._contact_forces(self.tip_links, None)

    def get_fsr_obj_force(self, obj: Actor | Link) -> torch.Tensor:
        """[N, 5, 3] contact force between each fingertip link and ``obj``, N."""
        return self._contact_forces(self.tip_links, obj)

    def get_fsr_impulse(self) -> torch.Tensor:
        """[N, 5, 3] net contact impulse on each fingertip over the last physics step, N·s."""
        return self.get_fsr_force() * self.scene.timestep

    def get_fsr_obj_impulse(self, obj: Actor | Link) -> torch.Tensor:
        """[N, 5, 3] contact impulse between each fingertip and ``obj`` over the last physics step, N·s."""
        return self.get_fsr_obj_force(obj) * self.scene.timestep

    def get_hand_group_obj_mean_force(self, obj: Actor | Link | Articulation) -> torch.Tensor:
        """[N, 6, 1] mean contact-force magnitude between ``obj`` and each link group (th, ff, mf, rf, lf, palm), N."""
        magnitude = torch.linalg.norm(self._contact_forces(self._group_link_list, obj), dim=-1)  # [N, L]
        sums = torch.zeros(magnitude.shape[0], len(HAND_GROUP_LINKS), device=self.device)
        sums.index_add_(1, self._group_index, magnitude)
        return (sums / self._group_sizes).unsqueeze(-1)

    def is_grasping(self, obj: Actor | Link, min_force: float = 0.5) -> torch.Tensor:
        """[N] bool: the thumb and at least one other finger press on ``obj`` with more than ``min_force`` N."""
        f = torch.linalg.norm(self.get_fsr_obj_force(obj), dim=-1)  # [N, 5]
        return (f[:, 0] > min_force) & (f[:, 1:] > min_force).any(dim=1)

