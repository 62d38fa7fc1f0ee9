"""ShadowHand grasp synthesis: palm poses sampled around an object's measured geometry, plus a closing synergy.

A grasp is planned from the object's *actual* pose (re-read after every disturbance), never from the nominal one:
with a 0.03 m object, a palm 5 mm off loses it. Two families cover the catalog's graspable objects:

- ``top`` — palm facing the table over a compact object (height ≤ :data:`TOP_GRASP_MAX_HEIGHT_M`), the object's
  centre :data:`TOP_ALONG_M` along the palm from the wrist, palm touching its top; the fingers curl down over the
  far side and the thumb comes under from the side.
- ``side`` — palm facing a tall object's axis from the side at :data:`SIDE_HEIGHT_FRACTION` of its height (thumb side
  down), fingers horizontal, the axis :data:`SIDE_ALONG_M` along the palm. The hand slides in along its fingers
  with the thumb already pre-shaped (:data:`SIDE_THUMB_PRE`) behind the object's wrist-side far quadrant; the
  fingers then curl over the far side and pull the object onto the thumb, which presses back toward the palm.

Candidates differ by the approach heading (yaw about the vertical); :func:`grasp_candidates` returns them all,
nearest-heading-first for a given preference, and the executor keeps the first one the arm can reach without
collision. Closing is *guarded*: each control step the finger targets are clipped to within
:data:`GUARD_RAD` of the measured angles, so a finger that touches the object stops and squeezes with about
stiffness × GUARD_RAD instead of flinging it (see ``docs/solving.md``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import sapien

PALM_THICKNESS_M = 0.011
"""Distance from the palm link origin to the palm's skin along the palm normal."""
TOP_ALONG_M = 0.075
"""Top grasp: object centre distance from the palm origin along the fingers (tuned: 0.065–0.075 lift 8/8)."""
TOP_GRASP_MAX_HEIGHT_M = 0.13
SIDE_ALONG_M = 0.09
"""Side grasp: object axis distance from the palm origin along the fingers (knuckles at 0.095). Tuned on the 66 mm
bottle (10 seeds, lift then 2 s hold): 0.08–0.10 all held; at 0.07 / 0.06 the thumb had lost contact after the
hold in 1 / 3 seeds. Further out the bottle tilts more while closing (≈ 30° at 0.10 against ≈ 22° at 0.08)."""
SIDE_GAP_M = 0.010
"""Side grasp: gap between the palm skin and the object (0.006–0.016 all lift)."""
SIDE_HEIGHT_FRACTION = 0.55
SIDE_MIN_HEIGHT_M = 0.10
"""Lowest side-grasp palm height above the object's bottom: with the thumb side down the pre-shaped thumb reaches
0.09 m below the palm origin."""
GUARD_RAD = 0.2
"""Guarded closing: finger targets stay within this of the measured joint angles (squeeze ≈ 15 N·m/rad × 0.2)."""

FINGER_FLEX_JOINTS = tuple(f + j for f in ("FF", "MF", "RF", "LF") for j in ("J2", "J1", "J0"))
"""Flexion joints of the four fingers (J0 is coupled to J1 by the controller, set anyway for clarity)."""
THUMB_JOINTS = ("THJ4", "THJ3", "THJ2", "THJ1", "THJ0")

OPEN_HAND = {"THJ4": 0.6} | {j: 0.0 for j in FINGER_FLEX_JOINTS}
"""Pre-grasp hand: fingers straight, thumb rotated out of the palm's way."""
FINGERS_CLOSED = {j: 1.3 for j in FINGER_FLEX_JOINTS}
"""Closing target of the fingers (beyond contact for every catalog object: the guard stops them)."""
THUMB_OPPOSED = {"THJ4": 0.0, "THJ3": 1.2, "THJ2": 0.0, "THJ1": -0.5, "THJ0": -1.0}
"""Thumb closing target: its tip reaches under the palm's centre (found by forward kinematics, 8/8 in sweeps)."""
SIDE_THUMB_PRE = {"THJ4": -0.5, "THJ3": 1.0, "THJ2": 0.0, "THJ1": -0.25, "THJ0": -1.0}
"""Side grasp, before closing: the thumb pad sits 10 mm off a 33 mm-radius object's surface at its far, wrist-side
quadrant (palm frame y −0.072, z 0.048; found by forward kinematics), and no thumb link lies in the object's band
beyond its axis, so the hand can slide in along its fingers without touching it."""
SIDE_THUMB_CLOSED = {"THJ4": 0.0, "THJ3": 0.7, "THJ2": 0.0, "THJ1": -0.25, "THJ0": -1.0}
"""Side grasp thumb target: from :data:`SIDE_THUMB_PRE`, raising THJ4 and lowering THJ3 both move the pad toward the
object's axis (≈ +0.04 and +0.06 m/rad), pressing it toward the palm and the fingers."""
SIDE_OPEN_HAND = {j: 0.0 for j in FINGER_FLEX_JOINTS} | SIDE_THUMB_PRE
"""Side pre-grasp hand: fingers straight (they slide along the object's near side), thumb pre-shaped behind it."""


@dataclass(frozen=True)
class GraspPlan:
    """One candidate grasp of an object, in world coordinates."""

    kind: str
    """``top`` or ``side``."""
    palm: sapien.Pose
    """Palm link pose when the hand closes."""
    approach: np.ndarray
    """[3] unit direction the palm travels in the last ``approach_m`` before closing."""
    approach_m: float = 0.10
    fingers: dict[str, float] = field(default_factory=lambda: dict(FINGERS_CLOSED))
    thumb: dict[str, float] = field(default_factory=lambda: dict(THUMB_OPPOSED))
    open_hand: dict[str, float] = field(default_factory=lambda: dict(OPEN_HAND))
    """Hand joints while the arm moves to the pre-grasp pose and approaches."""

    @property
    def pregrasp(self) -> sapien.Pose:
        return sapien.Pose(self.palm.p - self.approach_m * self.approach, self.palm.q)


def _pose(rot: np.ndarray, p: np.ndarray) -> sapien.Pose:
    m = np.eye(4)
    m[:3, :3] = rot
    m[:3, 3] = p
    return sapien.Pose(m)


def palm_rotation(fingers: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Rotation [3, 3] of the palm link whose fingers point along ``fingers`` and whose palm faces ``normal``.

    ShadowHand palm frame: +z runs along the fingers, the palm's skin faces -y, the thumb sits on +x.
    """
    z = fingers / np.linalg.norm(fingers)
    y = -normal / np.linalg.norm(normal)
    return np.column_stack([np.cross(y, z), y, z])


def headings(n: int, prefer_rad: float) -> np.ndarray:
    """``n`` yaw angles evenly around the circle, ordered by distance from ``prefer_rad``."""
    yaws = prefer_rad + np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    d = np.abs((yaws - prefer_rad + np.pi) % (2 * np.pi) - np.pi)
    order = np.argsort(d + 1e-6 * np.arange(n), kind="stable")
    return yaws[order]


def grasp_candidates(center_xy: np.ndarray, bottom_z: float, height_m: float, radius_m: float,
                     prefer_yaw_rad: float = 0.0, n: int = 12) -> list[GraspPlan]:
    """Grasp candidates for an upright object with its axis at ``center_xy``, resting at ``bottom_z``.

    ``prefer_yaw_rad`` is the finger heading tried first (usually away from the robot base).
    """
    up = np.array([0.0, 0.0, 1.0])
    out = []
    for yaw in headings(n, prefer_yaw_rad):
        f = np.array([np.cos(yaw), np.sin(yaw), 0.0])
        if height_m <= TOP_GRASP_MAX_HEIGHT_M:
            top = np.array([center_xy[0], center_xy[1], bottom_z + height_m])
            palm = top - TOP_ALONG_M * f + PALM_THICKNESS_M * up
            out.append(GraspPlan("top", _pose(palm_rotation(f, -up), palm), approach=-up))
        else:
            # palm faces the axis along n (horizontal, perpendicular to the fingers): this side puts the thumb down
            n_ = np.array([np.sin(yaw), -np.cos(yaw), 0.0])
            z = bottom_z + max(SIDE_HEIGHT_FRACTION * height_m, SIDE_MIN_HEIGHT_M)
            axis = np.array([center_xy[0], center_xy[1], z])
            palm = axis - SIDE_ALONG_M * f - (radius_m + SIDE_GAP_M + PALM_THICKNESS_M) * n_
            rot = palm_rotation(f, n_)
            out.append(GraspPlan("side", _pose(rot, palm), approach=f, thumb=dict(SIDE_THUMB_CLOSED),
                                 open_hand=dict(SIDE_OPEN_HAND)))
    return out
