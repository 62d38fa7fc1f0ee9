"""ShadowHand kinematics in the palm frame: where the fingertips and every hand link are for given finger joints,
and finger inverse kinematics that puts a fingertip pad on a point.

Grasp synthesis (:mod:`gendex.solve.grasp`) plans in the palm frame (+z along the fingers, the palm's skin facing
-y, the thumb on +x): it asks where a pad must be, solves the finger's joints with :meth:`HandModel.finger_ik`, and
checks with :meth:`HandModel.spheres` that the opened hand touches neither the table nor the object before it closes.
Forward kinematics uses the robot's Pinocchio model (:class:`~gendex.solve.ik.ArmIK`'s); the sphere cover comes from
the hand links' PhysX collision shapes, so it is the geometry the simulator collides.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial import cKDTree

from gendex.solve.ik import ArmIK
from gendex_envs.agents.ur10e_shadow import COUPLED_DISTAL, FINGER_JOINTS, TIP_LINKS, WRIST_JOINTS
from gendex_envs.physx import px_objects

FINGERS = ("th", "ff", "mf", "rf", "lf")
"""Finger names in the order of every per-finger array (thumb, index, middle, ring, little)."""
PAD_ALONG_M = 0.016
"""Where a fingertip pad is: this far along its distal link's axis (the capsule's centre line)."""
TIP_ALONG_M = 0.024
"""Where the fingertip's end is: the centre of the distal capsule's end cap (no part of the link lies beyond this
point by more than the capsule radius, whichever way the finger points)."""
PAD_RADIUS_M = {"th": 0.0092, "ff": 0.0071, "mf": 0.0071, "rf": 0.0071, "lf": 0.0071}
"""Radius of the distal capsules: a pad touches a surface when its axis point is this far from it."""
_FLEX = (("th", "THJ0", -1.0), ("ff", "FFJ1", 1.0), ("mf", "MFJ1", 1.0), ("rf", "RFJ1", 1.0), ("lf", "LFJ1", 1.0))
"""Each finger's last flexing joint and the sign of its flexion."""
IK_TOL_M = 0.002
"""A finger IK answer counts when its pad point is within this of the target."""
_SAMPLES = 2500
_SAMPLED: dict[tuple, dict[tuple[str, float], tuple[np.ndarray, cKDTree]]] = {}
"""Pad samples by hand kinematics (:meth:`HandModel._kinematics_key`): every solver of a process shares them, read
only (2.5 s a hand to compute; a solver is made per task and per attempt)."""
DIFF_STEP = 1e-4
"""Finite-difference step (relative, rad) of the fingertip pinch's least-squares solves (:mod:`gendex.solve.tip_pinch`).
Forward kinematics comes in float32 poses: at scipy's default step (~1e-8) a derivative is rounding noise, solves
stall where they start and their answers change with the last bits of any computation before them.
:func:`gendex.solve.grasp.pinch_shape` and :meth:`HandModel.finger_ik` still take scipy's step, so their answers are
those the published tasks were measured with. With this step there too, the knife held 12/20 and the hammer 13/20
on seeds 9500.. (without it, on seeds 9300..: 0/20 and 3/20), but every other pinch moved as well and three seeded
scenario tests of the rigid skills changed outcome: that change waits for a library-wide re-measure (the variant,
this step passed as ``diff_step`` to those two solves, was measured on a local branch that was not kept). The knife
has since been taken by the tip pinch instead (19/20 on seeds 9940..), and the hammer by a squeeze that grows with
the load (:data:`gendex.solve.grasp.MAX_SQUEEZE_GAIN`)."""


def actuated(finger: str) -> tuple[str, ...]:
    """The joints of ``finger`` an action drives (the coupled distal J0 follows J1)."""
    return tuple(j for j in FINGER_JOINTS[finger] if j not in COUPLED_DISTAL)


@dataclass(frozen=True)
class HandPose:
    """One forward-kinematics pass over the hand (palm frame): the fingertips' end caps and the sphere cover."""

    tips: np.ndarray
    """[5, 3] centres of the distal capsules' far end caps (th, ff, mf, rf, lf): a fingertip touches the table when
    its centre is :data:`PAD_RADIUS_M` above it."""
    distal: np.ndarray
    """[5, 3, 3] rotations of the distal links."""
    cover: SphereCover


@dataclass(frozen=True)
class SphereCover:
    """Spheres covering the hand's collision shapes in the palm frame: centres [S, 3], radii [S], and the finger
    (or ``palm``) each belongs to."""

    centers: np.ndarray
    radii: np.ndarray
    owner: np.ndarray


class HandModel:
    """Palm-frame forward and inverse kinematics of the ShadowHand of one robot."""

    def __init__(self, ik: ArmIK, robot):
        self.ik = ik
        self.names = list(ik.joint_names)
        self._index = {n: i for i, n in enumerate(self.names)}
        self._palm = ik.link_names.index("palm")
        self._tips = [ik.link_names.index(n) for n in TIP_LINKS]
        shapes = _hand_spheres(robot, ik.link_names)
        self._sphere_link = np.concatenate([np.full(len(r), link) for link, _, r, _ in shapes])
        self._sphere_local = np.concatenate([local for _, local, _, _ in shapes])
        self._sphere_radii = np.concatenate([r for _, _, r, _ in shapes])
        self._sphere_owner = np.concatenate([np.full(len(r), who) for _, _, r, who in shapes])
        self._hand_links = sorted({*self._sphere_link.tolist(), *self._tips, self._palm})
        self.tip_end = _tip_ends(robot)
        """Distance of each distal capsule's far end-cap centre along its link's z axis (th, ff, mf, rf, lf)."""
        key = self._kinematics_key()
        self._samples = _SAMPLED.get(key)
        if self._samples is None:
            self._samples = _SAMPLED[key] = self._sample_pads()

    def _kinematics_key(self) -> tuple:
        """What the pad samples depend on: the model's names and limits and where its pads are at two probe
        configurations (a hand whose kinematics differ in any way gets samples of its own)."""
        probe = {j: 0.5 * (lo + hi) for f in FINGERS for j, lo, hi in zip(actuated(f), *self.bounds(actuated(f)),
                                                                               strict=True)}
        return (tuple(self.names), tuple(self.ik.link_names), self.ik.limits.tobytes(), self.pads({}).tobytes(),
                self.pads(probe).tobytes(), self.pads(probe, TIP_ALONG_M).tobytes())

    def _sample_pads(self) -> dict[tuple[str, float], tuple[np.ndarray, cKDTree]]:
        """Per finger and pad point, :data:`_SAMPLES` random joint configurations (seeded) and a KD-tree of where the
        point is at each (palm frame): :meth:`finger_ik`'s starts and :meth:`reach_gap`'s test."""
        rng = np.random.default_rng(0)
        samples = {}
        for f in FINGERS:
            js = actuated(f)
            lo, hi = self.bounds(js)
            qs = rng.uniform(lo, hi, size=(_SAMPLES, len(js)))
            qs.flags.writeable = False  # shared between solvers
            for along in (PAD_ALONG_M, TIP_ALONG_M):
                pts = np.array([self.pads(dict(zip(js, q, strict=True)), along)[FINGERS.index(f)] for q in qs])
                samples[f, along] = (qs, cKDTree(pts))
        return samples

    # ------------------------------------------------------------------ forward kinematics
    def vector(self, hand: dict[str, float]) -> np.ndarray:
        """Full joint vector (arm and wrist at zero) with ``hand``'s joints set; coupled distal joints follow."""
        q = np.zeros(len(self.names))
        for j, v in hand.items():
            q[self._index[j]] = v
        for follower, leader in COUPLED_DISTAL.items():
            if leader in hand and follower not in hand:
                q[self._index[follower]] = hand[leader]
        for j in WRIST_JOINTS:
            q[self._index[j]] = 0.0
        return q

    def _link_frames(self, hand: dict[str, float]) -> tuple[np.ndarray, list[np.ndarray]]:
        model = self.ik.model
        model.compute_forward_kinematics(self.vector(hand))
        inv = np.linalg.inv(model.get_link_pose(self._palm).to_transformation_matrix())
        return inv, [inv @ model.get_link_pose(i).to_transformation_matrix() for i in range(len(self.ik.link_names))]

    def _hand_frames(self, hand: dict[str, float]) -> list[np.ndarray]:
        """Palm-frame transforms [4, 4] of the hand's links (identity for the arm's, which the hand never needs):
        :meth:`_link_frames` for the many calls of a least-squares solve (``np.linalg.inv`` costs ~1 ms a call when
        LAPACK threads contend for the cores)."""
        model = self.ik.model
        model.compute_forward_kinematics(self.vector(hand))
        inv = _rigid_inverse(model.get_link_pose(self._palm).to_transformation_matrix())
        frames = [_EYE4] * len(self.ik.link_names)
        for i in self._hand_links:
            frames[i] = inv @ model.get_link_pose(i).to_transformation_matrix()
        return frames

    def _tip_frames(self, hand: dict[str, float]) -> list[np.ndarray]:
        """The distal links' entries of :meth:`_link_frames` (th, ff, mf, rf, lf), computed alone: the same numbers,
        without the other links' transforms (the pad of a finger IK solve or of the samples needs only these)."""
        model = self.ik.model
        model.compute_forward_kinematics(self.vector(hand))
        inv = np.linalg.inv(model.get_link_pose(self._palm).to_transformation_matrix())
        return [inv @ model.get_link_pose(i).to_transformation_matrix() for i in self._tips]

    def pads(self, hand: dict[str, float], along: float = PAD_ALONG_M) -> np.ndarray:
        """[5, 3] pad points (th, ff, mf, rf, lf) in the palm frame: ``along`` the distal links' axes (the pads, or
        with :data:`TIP_ALONG_M` the fingertips' ends)."""
        return np.array([f[:3, :3] @ [0.0, 0.0, along] + f[:3, 3] for f in self._tip_frames(hand)])

    def pad_normals(self, hand: dict[str, float], eps: float = 1e-3, along: float = PAD_ALONG_M) -> np.ndarray:
        """[5, 3] unit directions the pads face (palm frame): where each pad moves when its finger's last joint
        flexes (the thumb's THJ0 flexes with negative angles)."""
        base = self.pads(hand, along)
        out = np.zeros((5, 3))
        for k, (f, joint, sign) in enumerate(_FLEX):
            bent = dict(hand)
            bent[joint] = hand.get(joint, 0.0) + sign * eps
            if f != "th":
                bent[joint.replace("J1", "J0")] = bent[joint]
            d = self.pads(bent, along)[k] - base[k]
            out[k] = d / max(np.linalg.norm(d), 1e-12)
        return out

    def pose(self, hand: dict[str, float]) -> HandPose:
        """Fingertip end caps, distal orientations and sphere cover from one forward-kinematics pass."""
        return self._pose_from(self._hand_frames(hand))

    def _pose_from(self, frames: list[np.ndarray]) -> HandPose:
        tips = np.array([frames[i][:3, :3] @ [0.0, 0.0, e] + frames[i][:3, 3]
                         for i, e in zip(self._tips, self.tip_end, strict=True)])
        return HandPose(tips, np.array([frames[i][:3, :3] for i in self._tips]), self._cover(frames))

    def spheres(self, hand: dict[str, float]) -> SphereCover:
        """Sphere cover of the hand at ``hand``'s joints, palm frame."""
        _, frames = self._link_frames(hand)
        return self._cover(frames)

    def _cover(self, frames: list[np.ndarray]) -> SphereCover:
        m = np.asarray(frames)[self._sphere_link]  # [S, 4, 4]
        centers = np.einsum("sij,sj->si", m[:, :3, :3], self._sphere_local) + m[:, :3, 3]
        return SphereCover(centers, self._sphere_radii, self._sphere_owner)

    # ------------------------------------------------------------------ inverse kinematics
    def bounds(self, joints) -> tuple[np.ndarray, np.ndarray]:
        lim = self.ik.limits
        return (np.array([lim[self._index[j], 0] for j in joints]), np.array([lim[self._index[j], 1] for j in joints]))

    def reach_gap(self, finger: str, points: np.ndarray, along: float = PAD_ALONG_M) -> np.ndarray:
        """[P] distance from each palm-frame point to the nearest sampled pad position of ``finger`` (a cheap test
        of whether the pad can get there)."""
        return self._samples[finger, along][1].query(np.atleast_2d(points))[0]

    def finger_ik(self, finger: str, target: np.ndarray, prefer: dict[str, float] | None = None,
                  along: float = PAD_ALONG_M) -> tuple[dict[str, float], float]:
        """Joints of ``finger`` (its actuated ones) putting its pad point (``along`` its distal axis) on ``target``
        (palm frame), and the remaining distance (m). Starts from the nearest sampled configurations; ``prefer``
        breaks ties."""
        js = actuated(finger)
        lo, hi = self.bounds(js)
        k = FINGERS.index(finger)
        qs, tree = self._samples[finger, along]
        _, idx = tree.query(np.asarray(target, float), k=3)
        starts = [qs[i] for i in np.atleast_1d(idx)]
        if prefer is not None:
            starts.insert(0, np.clip([prefer.get(j, 0.0) for j in js], lo, hi))
        best: tuple[np.ndarray, float] | None = None
        for x0 in starts:
            sol = least_squares(lambda x: self.pads(dict(zip(js, x, strict=True)), along)[k] - target,
                                np.clip(x0, lo + 1e-6, hi - 1e-6), bounds=(lo, hi), xtol=1e-6)
            err = float(np.linalg.norm(sol.fun))
            if best is None or err < best[1] - 1e-4:
                best = (sol.x, err)
            if err < IK_TOL_M / 4:
                break
        return dict(zip(js, (float(v) for v in best[0]), strict=True)), best[1]


_EYE4 = np.eye(4)


def _rigid_inverse(m: np.ndarray) -> np.ndarray:
    """Inverse of a rigid transform [4, 4]."""
    out = np.eye(4)
    out[:3, :3] = m[:3, :3].T
    out[:3, 3] = -m[:3, :3].T @ m[:3, 3]
    return out


@functools.cache
def _unit_grid(n: int) -> np.ndarray:
    return np.linspace(-1.0, 1.0, n)


def _tip_ends(robot) -> tuple[float, ...]:
    """Far end-cap centre of each distal link's capsule along the link's z axis (th, ff, mf, rf, lf)."""
    from sapien import physx

    from gendex_envs.agents.ur10e_shadow import TIP_LINKS

    links = {link.name: link for link in robot.get_links()}
    out = []
    for name in TIP_LINKS:
        caps = [s for s in px_objects(links[name])[0].collision_shapes
                if isinstance(s, physx.PhysxCollisionShapeCapsule)]
        ends = []
        for cap in caps:  # PhysX capsules lie along their local x axis
            m = cap.local_pose.to_transformation_matrix()
            ends += [float((m[:3, :3] @ [sign * cap.half_length, 0.0, 0.0] + m[:3, 3])[2]) for sign in (-1, 1)]
        out.append(max(ends) if ends else TIP_ALONG_M)
    return tuple(out)


def _hand_spheres(robot, link_names: list[str]) -> list[tuple[int, np.ndarray, np.ndarray, str]]:
    """(link index, local centres [k, 3], radii [k], owner) covering every collision shape of the palm and fingers."""
    from sapien import physx

    owners = {"palm": "palm"}
    for f in FINGERS:
        for link in robot.get_links():
            if link.name.startswith(f) or (f == "th" and link.name == "thbase"):
                owners[link.name] = f
    owners["lfmetacarpal"] = "lf"
    out = []
    for link in robot.get_links():
        if link.name not in owners:
            continue
        for shape in px_objects(link)[0].collision_shapes:
            m = shape.local_pose.to_transformation_matrix()
            if isinstance(shape, physx.PhysxCollisionShapeCapsule):  # along local x
                r, h = shape.radius, shape.half_length
                n = max(2, int(np.ceil(2 * h / r)) + 1)
                local = np.stack([_unit_grid(n) * h, np.zeros(n), np.zeros(n)], axis=1)
                radii = np.full(n, r)
            elif isinstance(shape, physx.PhysxCollisionShapeBox):
                hs = np.asarray(shape.half_size)
                r = float(hs.min())
                axes = [_unit_grid(max(1, int(np.ceil(h / r)) + 1)) * max(h - r, 0.0) for h in hs]
                local = np.array([[x, y, z] for x in axes[0] for y in axes[1] for z in axes[2]])
                radii = np.full(len(local), 1.2 * r)  # a little fatter: the box edges between the centres
            else:
                continue
            out.append((link_names.index(link.name), local @ m[:3, :3].T + m[:3, 3], radii, owners[link.name]))
    return out
