"""ShadowHand grasp synthesis over an object's geometry: a family chosen from shape and size, candidate palm poses
and hand shapes, and the kinematic checks that come before any physics.

A grasp is always planned from the object's *measured* pose and its collision geometry (:mod:`gendex.solve.shape`),
never from the nominal layout. Three families cover the catalog's graspable objects:

- ``pinch`` — a precision grip: the thumb pad and the index pad (with the middle finger beside it where it
  reaches) squeeze the object along a line through it. The lines are horizontal: across the narrow side of an
  elongated object at several places along it (knife, marker, banana, a hammer's handle), through the centre of a
  compact one at several headings (dice, golf ball, blocks), or through one wall near the rim of a hollow one
  (bowl, plate, pot, pitcher: thumb inside or outside). Where the line enters and leaves material gives the two
  contact points; finger inverse kinematics (:mod:`gendex.solve.hand`) gives the pre-shape (pads
  :data:`PINCH_OPEN_M` outside the contacts), and the closing target (pads :data:`PINCH_SQUEEZE_M` inside). The
  palm is placed where both pads reach: for each of a few palm orientations about the pinch line, the pinch centre
  in the palm frame is solved together with the finger joints (:func:`pinch_shape`, cached by width).
- ``top`` — a power grasp of a compact object from above: palm facing the table on its top, the object's centre
  :data:`TOP_ALONG_M` along the palm from the wrist; the fingers curl over the far side and the thumb comes under
  from the side.
- ``side`` — a power grasp of a tall object: palm facing its axis from the side at :data:`SIDE_HEIGHT_FRACTION` of
  its height (thumb side down), fingers horizontal; the hand slides in along its fingers with the thumb pre-shaped
  (:data:`SIDE_THUMB_PRE`) behind the object's wrist-side far quadrant, the fingers pull it onto the thumb.

:class:`GraspSynthesizer` yields candidates in order of preference (the families that suit the object's size first,
then by heading nearest the preferred one); each has passed the kinematic check that the opened hand, at the
pre-grasp pose and along its approach, stays clear of the table and of the object. The executor then keeps those the
arm reaches without collision and ranks them by a short physics trial (:mod:`gendex.solve.grasp_trial`).
Closing is *guarded*: each control step the finger targets are clipped to within :data:`GUARD_RAD` of the measured
angles, so a finger that touches the object stops and squeezes with about stiffness x GUARD_RAD instead of flinging
it (see ``docs/solving.md``).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Generator, Iterator
from dataclasses import dataclass, field

import numpy as np
import sapien
from scipy.optimize import least_squares

from gendex.solve.hand import FINGERS, PAD_ALONG_M, PAD_RADIUS_M, TIP_ALONG_M, HandModel, actuated
from gendex.solve.shape import PosedShape

HAND_SPAN_M = 0.09
"""Widest object (smallest horizontal extent, m) the ShadowHand closes around reliably. Tasks fit a grasped object
wider than this to the hand by scaling it down (:func:`hand_fit_scale`; the generator's size step does it)."""
PALM_THICKNESS_M = 0.011
"""Distance from the palm link origin to the palm's skin along the palm normal."""
GUARD_RAD = 0.2
"""Guarded closing: finger targets stay within this of the measured joint angles (squeeze ≈ 15 N·m/rad × 0.2)."""

# ---------------------------------------------------------------------------------------------- power grasps
TOP_ALONG_M = 0.075
"""Top grasp: object centre distance from the palm origin along the fingers (tuned: 0.065–0.075 lift 8/8)."""
TOP_MAX_HEIGHT_M = 0.13
TOP_MIN_SIZE_M = 0.05
"""Top grasps need an object at least this wide (smaller ones slip between the curled fingers and the thumb)."""
TOP_MAX_SIZE_M = 0.115
"""...and at most this wide across the fingers (the curled fingers' reach)."""
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
SIDE_MAX_DEPTH_M = 0.095
"""Side grasps need the object at most this thick along the palm normal (the fingers wrap its far side)."""

FINGER_FLEX_JOINTS = tuple(f + j for f in ("FF", "MF", "RF", "LF") for j in ("J2", "J1", "J0"))
"""Flexion joints of the four fingers (J0 is coupled to J1 by the controller, set anyway for clarity)."""
THUMB_JOINTS = ("THJ4", "THJ3", "THJ2", "THJ1", "THJ0")

OPEN_HAND = {"THJ4": 0.6} | {j: 0.0 for j in FINGER_FLEX_JOINTS}
"""Pre-grasp hand: fingers straight, thumb rotated out of the palm's way."""
RELEASE_HAND = OPEN_HAND | {"THJ3": 0.0, "THJ1": 0.0, "THJ0": 0.0}
"""Hand of a release: every finger straight, the thumb out."""
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

# ---------------------------------------------------------------------------------------------- pinch
PINCH_MAX_WIDTH_M = 0.09
"""Widest pinch: thumb and index pads reach each other's side across at most this much material (at 0.07 the 84 mm
tuna can had no pinch and no top grasp held it: 0/20; at 0.09 it is pinched 20/20, the other objects unchanged)."""
PINCH_FIT_M = 0.085
"""A pinch of an object wider than this at its middle is also tried where it is this wide, above the middle."""
ELONGATED = 1.6
"""An object whose footprint is this many times longer than wide is pinched across its long axis."""
CENTROID_APART_M = 0.005
"""An elongated object is also pinched across its centroid (its centre of mass, uniform density) when that is this
far from every other place its pinches are tried; places nearer the centroid are tried first (a 0.41 kg hammer
pinched 20 mm from it twisted out of the pads)."""
TALL_M = 0.08
"""An object taller than this is pinched level with its centroid first (then at the usual heights), unless it is too
wide to pinch at its middle (then in the usual order: low, then where it fits above its middle, as
:meth:`GraspSynthesizer._widest_fit` finds). Pinched 3 cm up, a can (12 cm, 0.35 kg) turned about the pinch line as it
rose and slid down the pads: 37/40 on dev seeds 782000-782039, 40/40 pinched at its centroid's height, and the five
attempts it failed in the grasp records of seeds 10000-10039 all hold. A softball pinched at its equator was lifted
as well but did a little worse in the tasks that carry it (PutSoftballInPot-v1 and PutSoftballInBowlLarge-v0, seeds
267000-267049: 95/100, against 98/100 in the usual order, which holds it above its middle)."""
PINCH_OPEN_M = 0.022
"""Pre-shape: each pad this far outside its contact point along the pinch line."""
PINCH_SQUEEZE_M = 0.02
"""Closing target: each pad this far inside its contact point (the guard stops it on the surface)."""
SQUEEZE_REF_KG = 0.2
MAX_SQUEEZE_GAIN = 2.0
"""A pinch across an elongated object heavier than :data:`SQUEEZE_REF_KG` closes further past first contact: the
thumb's, the index's and the middle finger's closing targets lead the touching hand (joint space) by the planned lead
times the mass over that, at most :data:`MAX_SQUEEZE_GAIN` (a grip that grows with the load, as a person's does; the
guard still caps the lead at :data:`GUARD_RAD`). Across a handle the object's weight mostly acts off the pinch line
and twists it out of two pads: a 0.42 kg hammer pinched with the plain lead pressed at 1-3 N a pad and slid out while
it rose (benchmarks/grasp.py: 30 % in the record of seeds 9940-9959, 6/20 on 9960-9979); squeezed so, 20/20 on
9960-9979 and on 9980-9999. With the index and the thumb alone squeezed harder, 15/20 on 9980-9999 and 20/20 on
10000-10019: the middle finger along the handle helps hold the twist.

A compact object keeps the plain lead. Squeezed harder, pinches that had held a can (0.35 kg) or a sugar box (0.51 kg)
well enough let them turn in the hand while carried: SetCanOnTray-v1 15/20 against 18/20 (seeds 263000-263019, the
middle finger scaled too), SetSugarBoxOnPlate-v1 37/40 against 40/40 (265000-265019 and 266000-266019, thumb and
index only)."""
PINCH_AXES_PALM = ((-0.43, 0.25, 0.87), (-0.25, 0.43, 0.87), (-0.5, 0.0, 0.87), (0.0, 0.5, 0.87))
"""Directions of the pinch line (thumb pad to index pad) in the palm frame where both pads reach and face each other
at 1–7 cm widths (a search over 60 directions): mostly along the fingers, the thumb nearer the wrist and the index
curled back towards it."""
MIN_FACING = 0.3
"""A pinch's pads must face each other: each pad's closing direction has at least this component along the line."""
PINCH_ROLLS_RAD = (0.0, -0.35, 0.35, -0.7, 0.7)
"""Palm orientations tried about the pinch line, from the one whose palm faces the table most squarely."""
TUCKED = {"RFJ2": 1.4, "RFJ1": 1.2, "LFJ2": 1.4, "LFJ1": 1.2, "LFJ4": 0.0, "RFJ3": 0.0, "LFJ3": 0.0}
"""Ring and little fingers of a pinch: curled out of the way."""
STRAIGHT = {"RFJ2": 0.0, "RFJ1": 0.0, "LFJ2": 0.0, "LFJ1": 0.0, "LFJ4": 0.0, "RFJ3": 0.0, "LFJ3": 0.0}
MIDDLE_TUCKED = {"MFJ3": 0.0, "MFJ2": 1.4, "MFJ1": 1.2}
TABLE_CLEARANCE_M = 0.0
MAX_RAISE_M = 0.006
"""A pinch whose open hand would dip into the table by at most this much is raised clear of it."""
RAISE_MARGIN_M = 1e-4
"""...by this much more than the dip: raised exactly to the table, the pose's float32 rounding left about half of
those hands a hair (~1e-8 m) below it, and the clearance check rejected them (a marker lying across the robot's view
had no pinch at all)."""
PAD_LIFT_M = 0.001
"""A pad's lowest point stays this far above the table: an object thinner than the pads is pinched at its edges by
fingertips that skim the table."""
OBJECT_CLEARANCE_M = 0.001
TIP_MAX_HEIGHT_M = 0.02
"""Objects at most this tall are also given fingertip pinches at the table (:mod:`gendex.solve.tip_pinch`)."""
APPROACH_M = 0.08
"""Straight final approach of the open hand (m)."""


@dataclass(frozen=True)
class GraspPlan:
    """One candidate grasp of an object, in world coordinates."""

    kind: str
    """``pinch``, ``top`` or ``side``."""
    palm: sapien.Pose
    """Palm link pose when the hand closes."""
    approach: np.ndarray
    """[3] unit direction the palm travels in the last ``approach_m`` before closing."""
    approach_m: float = 0.10
    open_hand: dict[str, float] = field(default_factory=lambda: dict(OPEN_HAND))
    """Hand joints while the arm moves to the pre-grasp pose and approaches."""
    clear_until_m: float = 0.0
    """The open hand keeps clear of the object on the approach until this far before the grasp pose (a top grasp's
    palm ends on the object)."""
    closing: tuple[tuple[dict[str, float], int], ...] = ((dict(FINGERS_CLOSED), 12), (dict(THUMB_OPPOSED), 12))
    """Guarded ramps that close the hand, in order: (joint targets, control steps)."""
    note: str = ""
    """What the candidate is (family, heading, width), for logs."""
    lift: Callable[[float], Generator[np.ndarray, None, float]] | None = None
    """The object's own lift after closing (an edge pinch's: kept whole, unhurried, as far as the arm reaches), given
    the motion's metres per step: yields joint targets and returns how far the palm rose; None: straight up by the
    motion's ``lift_m``."""

    @property
    def pregrasp(self) -> sapien.Pose:
        return sapien.Pose(self.palm.p - self.approach_m * self.approach, self.palm.q)

    @property
    def closed_hand(self) -> dict[str, float]:
        """Every joint target of the closing ramps (later ramps win)."""
        out: dict[str, float] = {}
        for targets, _ in self.closing:
            out |= targets
        return out

    def __str__(self) -> str:
        return f"{self.kind} grasp ({self.note})" if self.note else f"{self.kind} grasp"


def pose_of(rot: np.ndarray, p: np.ndarray) -> sapien.Pose:
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


def axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix [3, 3] of ``angle`` rad right-handed about unit ``axis`` (Rodrigues)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * k @ k


def _frame(x: np.ndarray, y_hint: np.ndarray) -> np.ndarray:
    """Orthonormal columns (x, y, z) with x along ``x`` and y as close to ``y_hint`` as possible."""
    x = x / np.linalg.norm(x)
    y = y_hint - np.dot(y_hint, x) * x
    y /= np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])


# ---------------------------------------------------------------------------------------------- pinch shapes
@dataclass(frozen=True)
class PinchShape:
    """A thumb-index pinch of one width along one palm-frame direction: where its centre lies in the palm frame and
    the finger joints of the open, touching and closing hand."""

    axis: np.ndarray
    """[3] unit pinch direction (thumb pad to index pad), palm frame."""
    center: np.ndarray
    """[3] midpoint between the contact points, palm frame."""
    contact: dict[str, float]
    open: dict[str, float]
    close: dict[str, float]
    middle: bool
    """The middle finger helps (its pad beside the index's) rather than being tucked away."""


@functools.lru_cache(maxsize=512)
def _pinch_shape_cached(hand_id: int, axis: tuple[float, float, float], width_mm: int, tips: bool
                        ) -> PinchShape | None:
    hand = _HANDS[hand_id]
    return _solve_pinch(hand, np.asarray(axis, float) / np.linalg.norm(axis), width_mm / 1000.0,
                        TIP_ALONG_M if tips else PAD_ALONG_M)


_HANDS: dict[int, HandModel] = {}


def pinch_shape(hand: HandModel, axis: tuple[float, float, float], width_m: float, tips: bool = False
                ) -> PinchShape | None:
    """The pinch of ``width_m`` (rounded up to 5 mm) along palm direction ``axis``, or None when the thumb and index
    cannot both reach (cached). ``tips``: squeeze with the fingertips' ends instead of the pads (objects lying low on
    the table: nothing of the finger then reaches lower than the contact)."""
    _HANDS[id(hand)] = hand
    return _pinch_shape_cached(id(hand), tuple(axis), int(5 * math.ceil(max(width_m, 0.0) * 200)), tips)


_CENTER_GRID = np.stack(np.meshgrid(np.arange(-0.02, 0.12, 0.008), np.arange(-0.11, -0.02, 0.008),
                                     np.arange(0.02, 0.16, 0.008), indexing="ij"), axis=-1).reshape(-1, 3)
"""Pinch centres (palm frame) searched for one where both pads reach."""


def _solve_pinch(hand: HandModel, a: np.ndarray, w: float, along: float) -> PinchShape | None:
    th, ff = actuated("th"), actuated("ff")
    off_t, off_f = w / 2 + PAD_RADIUS_M["th"], w / 2 + PAD_RADIUS_M["ff"]
    # centres from which both pad targets lie near sampled pad positions, nearest first
    gap = np.maximum(hand.reach_gap("th", _CENTER_GRID - off_t * a, along),
                     hand.reach_gap("ff", _CENTER_GRID + off_f * a, along))
    best = None
    for c0 in _CENTER_GRID[np.argsort(gap)[:4]]:
        q_t, _ = hand.finger_ik("th", c0 - off_t * a, along=along)
        q_f, _ = hand.finger_ik("ff", c0 + off_f * a, along=along)
        lo_t, hi_t = hand.bounds(th)
        lo_f, hi_f = hand.bounds(ff)
        lo = np.concatenate([c0 - 0.02, lo_t, lo_f])
        hi = np.concatenate([c0 + 0.02, hi_t, hi_f])

        def residual(x: np.ndarray) -> np.ndarray:
            joints = dict(zip(th + ff, x[3:], strict=True))
            pads = hand.pads(joints, along)
            normals = hand.pad_normals(joints, along=along)
            return np.concatenate([pads[0] - (x[:3] - off_t * a), pads[1] - (x[:3] + off_f * a),
                                   [0.01 * (normals[0] @ a - 1.0), 0.01 * (-normals[1] @ a - 1.0)]])

        x0 = np.concatenate([c0, [q_t[j] for j in th], [q_f[j] for j in ff]])
        sol = least_squares(residual, np.clip(x0, lo + 1e-7, hi - 1e-7), bounds=(lo, hi))
        err = float(np.linalg.norm(sol.fun[:6]))
        joints = dict(zip(th + ff, (float(v) for v in sol.x[3:]), strict=True))
        normals = hand.pad_normals(joints, along=along)
        facing = min(normals[0] @ a, -normals[1] @ a)
        if err < 0.002 and facing > MIN_FACING and (best is None or facing > best[2]):
            best = (sol.x[:3].copy(), joints, facing)
    if best is None:
        return None
    c, contact, _ = best
    out_t, e1 = hand.finger_ik("th", c - (off_t + PINCH_OPEN_M) * a, prefer=contact, along=along)
    out_f, e2 = hand.finger_ik("ff", c + (off_f + PINCH_OPEN_M) * a, prefer=contact, along=along)
    if max(e1, e2) > 0.008:
        return None  # cannot open wide enough around it
    in_t, _ = hand.finger_ik("th", c - (off_t - PINCH_SQUEEZE_M) * a, prefer=contact, along=along)
    in_f, _ = hand.finger_ik("ff", c + (off_f - PINCH_SQUEEZE_M) * a, prefer=contact, along=along)
    open_, close = out_t | out_f, in_t | in_f
    # the middle finger's pad beside the index's (towards the little finger), if it reaches
    side = np.array([-0.022, 0.0, 0.0])
    mid_c, e3 = hand.finger_ik("mf", c + off_f * a + side, along=along)
    middle = e3 < 0.004
    if middle:
        mid_o, _ = hand.finger_ik("mf", c + (off_f + PINCH_OPEN_M) * a + side, prefer=mid_c, along=along)
        mid_i, _ = hand.finger_ik("mf", c + (off_f - PINCH_SQUEEZE_M) * a + side, prefer=mid_c, along=along)
        contact, open_, close = contact | mid_c, open_ | mid_o, close | mid_i
    return PinchShape(a, c, contact, open_, close, middle)


# ---------------------------------------------------------------------------------------------- synthesizer
@dataclass(frozen=True)
class PinchLine:
    """Where a pinch squeezes: thumb contact, index contact (world), and what kind of line it is."""

    thumb: np.ndarray
    finger: np.ndarray
    note: str
    low: bool = False
    """The object is too thin for the pads: the fingertips' ends squeeze it, just above the table."""

    @property
    def width(self) -> float:
        return float(np.linalg.norm(self.finger - self.thumb))

    @property
    def axis(self) -> np.ndarray:
        return (self.finger - self.thumb) / max(self.width, 1e-9)

    @property
    def center(self) -> np.ndarray:
        return (self.thumb + self.finger) / 2


class GraspSynthesizer:
    """Grasp candidates of one object at its current pose (see the module docstring)."""

    def __init__(self, hand: HandModel, shape: PosedShape, table_z: float = 0.0, prefer_yaw_rad: float = 0.0,
                 others: tuple[PosedShape, ...] = (), mass_kg: float = 0.0, high_first: bool = False):
        self.hand = hand
        self.high_first = high_first
        """Pinch highest first: a peg goes into its hole bottom first, the fingers curled under a pinch at its middle
        met the holder's top before the peg's end reached the hole (seed 57618305)."""
        self.shape = shape
        self.table_z = table_z
        self.prefer = prefer_yaw_rad
        self.others = others
        """Other objects the open hand must not touch either."""
        self.squeeze = squeeze_gain(mass_kg)
        """Multiplier of the closing lead of a pinch across an elongated object (:func:`squeeze_gain` of its
        mass)."""
        self.fp = shape.footprint()

    # ------------------------------------------------------------------ order
    def families(self) -> list[str]:
        """Families that suit the object, best first."""
        fp = self.fp
        out = []
        tall = fp.height > TOP_MAX_HEIGHT_M
        if tall and self._side_depth() <= SIDE_MAX_DEPTH_M:
            out.append("side")
        if not tall and TOP_MIN_SIZE_M <= fp.width and fp.length <= TOP_MAX_SIZE_M:
            out.append("top")
        out.append("pinch")
        if fp.height <= TIP_MAX_HEIGHT_M:
            out.append("tip")
        return out

    def candidates(self) -> Iterator[GraspPlan]:
        """Kinematically checked candidates. Families take turns (the one that suits the object best first), so a
        short list of trials already holds different kinds of grasp; of each group of alternatives a family yields
        (the same grasp with the idle fingers placed differently) the first whose hand is clear."""
        gens = {"top": self._top, "side": self._side, "pinch": self._pinch, "tip": self._tip}
        streams = [self._clear(gens[f]()) for f in self.families()]
        while streams:
            for stream in list(streams):
                plan = next(stream, None)
                if plan is None:
                    streams.remove(stream)
                else:
                    yield plan

    def _clear(self, groups: Iterator[list[GraspPlan]]) -> Iterator[GraspPlan]:
        for group in groups:
            plan = next((p for p in group if self.hand_clear(p)), None)
            if plan is not None:
                yield plan

    # ------------------------------------------------------------------ kinematic check
    def hand_clear(self, plan: GraspPlan, samples: int = 4) -> bool:
        """The opened hand stays off the table and off the object from the pre-grasp pose to the grasp pose."""
        return self.path_clear(plan.open_hand, plan.palm, -plan.approach_m * plan.approach,
                               -plan.clear_until_m * plan.approach, samples)

    def path_clear(self, hand: dict[str, float], palm: sapien.Pose, start: np.ndarray, end: np.ndarray,
                   samples: int = 4) -> bool:
        """The hand at joints ``hand`` stays off the table and off every object while the palm moves from ``palm``
        shifted by ``start`` to ``palm`` shifted by ``end`` (world offsets, orientation kept)."""
        cover = self.hand.spheres(hand)
        m = palm.to_transformation_matrix()
        world = cover.centers @ m[:3, :3].T + m[:3, 3]
        for t in np.linspace(0.0, 1.0, samples + 1):
            pts = world + (1 - t) * np.asarray(start) + t * np.asarray(end)
            if np.any(self.table_gap(pts, cover.radii) < TABLE_CLEARANCE_M):
                return False
            for shape in (self.shape, *self.others):
                if np.any(shape.signed_distance(pts) - cover.radii < OBJECT_CLEARANCE_M):
                    return False
        return True

    def table_gap(self, centers: np.ndarray, radii: np.ndarray) -> np.ndarray:
        """[n] how far each sphere (world ``centers`` [n, 3], ``radii`` [n]) is above the table (negative: in it)."""
        return centers[:, 2] - radii - self.table_z

    # ------------------------------------------------------------------ families
    def _top(self) -> Iterator[list[GraspPlan]]:
        fp, up = self.fp, np.array([0.0, 0.0, 1.0])
        for yaw in headings(12, self.prefer):
            f = np.array([np.cos(yaw), np.sin(yaw), 0.0])
            top = np.array([fp.center[0], fp.center[1], fp.top])
            palm = top - TOP_ALONG_M * f + PALM_THICKNESS_M * up
            pose = pose_of(palm_rotation(f, -up), palm)
            yield [GraspPlan("top", pose, approach=-up, clear_until_m=0.015, note=f"heading {math.degrees(yaw):.0f}°")]
            # the same, fingers and thumb closing together: a round object is not pushed towards the thumb first
            yield [GraspPlan("top", pose, approach=-up, clear_until_m=0.015,
                             closing=((FINGERS_CLOSED | THUMB_OPPOSED, 14),),
                             note=f"heading {math.degrees(yaw):.0f}°, all fingers at once")]

    def _side_depth(self, yaw: float | None = None) -> float:
        """Thickness of the object along the palm normal of a side grasp at ``yaw`` (default: the widest)."""
        fp = self.fp
        if yaw is None:
            return fp.width
        n = np.array([np.sin(yaw), -np.cos(yaw), 0.0])
        lo, hi = self.shape.extent_along(n)
        return hi - lo

    def _side(self) -> Iterator[list[GraspPlan]]:
        fp = self.fp
        for yaw in headings(12, self.prefer):
            depth = self._side_depth(yaw)
            if depth > SIDE_MAX_DEPTH_M:
                continue
            f = np.array([np.cos(yaw), np.sin(yaw), 0.0])
            n = np.array([np.sin(yaw), -np.cos(yaw), 0.0])  # palm faces the axis along n: the thumb side down
            z = fp.bottom + max(SIDE_HEIGHT_FRACTION * fp.height, SIDE_MIN_HEIGHT_M)
            lo, hi = self.shape.extent_along(n)
            c = np.array([fp.center[0], fp.center[1], z])
            near = c + (lo - c[:2] @ n[:2]) * n  # the object's surface nearest the palm, on the axis line
            axis = near + depth / 2 * n
            palm = axis - SIDE_ALONG_M * f - (depth / 2 + SIDE_GAP_M + PALM_THICKNESS_M) * n
            yield [GraspPlan("side", pose_of(palm_rotation(f, n), palm), approach=f, open_hand=dict(SIDE_OPEN_HAND),
                             closing=((dict(FINGERS_CLOSED), 12), (dict(SIDE_THUMB_CLOSED), 12)),
                             note=f"heading {math.degrees(yaw):.0f}°, depth {1000 * depth:.0f} mm")]

    def pinch_lines(self) -> list[PinchLine]:
        """Pinch lines through the object (see the module docstring), most promising first."""
        fp = self.fp
        up = np.array([0.0, 0.0, 1.0])
        h = fp.height
        heights = [fp.bottom + min(h / 2, 0.03)]
        if h > 0.04:
            heights.append(fp.top - 0.012)
        axis3 = np.array([fp.axis[0], fp.axis[1], 0.0])
        across3 = np.cross(up, axis3)
        fit = self._widest_fit(across3)
        if fit is not None and min(abs(fit - z) for z in heights) > 0.005:
            heights.insert(1, fit)
        com = self.shape.centroid()
        if h > TALL_M and fit is None:  # level with the centre of mass first: the weight pulls along the pads
            heights = [float(com[2])] + [z for z in heights if abs(z - float(com[2])) > 0.005]
        if self.high_first:
            heights = sorted(heights, reverse=True)
        s_com = 0.0
        if self._elongated():  # across it, at several places along it, its centroid first
            s_com = float((com[:2] - fp.center) @ fp.axis)
            places = [s * fp.length for s in (0.0, -0.15, 0.15, -0.3, 0.3)]
            if min(abs(s_com - s) for s in places) > CENTROID_APART_M:
                places.append(s_com)
            dirs = [(sign * across3, s) for s in places for sign in (1, -1)]
        else:
            dirs = [(np.array([np.cos(y), np.sin(y), 0.0]), 0.0) for y in headings(8, self.prefer)]
        # the fingers point roughly along the pinch line: lines heading away from the robot first
        away = np.array([np.cos(self.prefer), np.sin(self.prefer), 0.0])
        dirs.sort(key=lambda ds: (-round(float(ds[0] @ away), 1), abs(ds[1] - s_com)))
        lines = []
        for z in heights:
            for d, s in dirs:
                c = np.array([fp.center[0], fp.center[1], z]) + s * axis3
                origin = c - 0.5 * d
                spans = self.shape.ray_intervals(origin, d)
                if not spans:
                    continue
                options = [(spans[0][0], spans[-1][1], "across")]
                if len(spans) > 1:
                    options.append((spans[0][0], spans[0][1], "wall"))
                up_t = max(0.0, self.table_z + PAD_RADIUS_M["th"] + PAD_LIFT_M - z)
                up_f = max(0.0, self.table_z + PAD_RADIUS_M["ff"] + PAD_LIFT_M - z)
                for t0, t1, what in options:
                    if t1 - t0 <= PINCH_MAX_WIDTH_M:
                        note = f"{what} at {1000 * (z - fp.bottom):.0f} mm, {1000 * s:+.0f} mm along"
                        lines.append(PinchLine(origin + t0 * d + [0.0, 0.0, up_t], origin + t1 * d + [0.0, 0.0, up_f],
                                               note, low=up_t > 0))
        return lines

    def _elongated(self) -> bool:
        """The object's footprint is long enough to be pinched across its long axis."""
        return self.fp.length > ELONGATED * self.fp.width

    def _widest_fit(self, across: np.ndarray) -> float | None:
        """The lowest height above the object's middle where a pinch across it (along ``across``) fits in
        :data:`PINCH_FIT_M`, for objects wider than that at their middle (a ball: there the pads press it down
        into the fingers rather than out of them); None when the middle fits already or nothing does."""
        fp = self.fp
        c = np.array([fp.center[0], fp.center[1], 0.0])

        def width(z: float) -> float | None:
            spans = self.shape.ray_intervals(c + [0.0, 0.0, z] - 0.5 * across, across)
            return spans[-1][1] - spans[0][0] if spans else None

        mid = fp.bottom + fp.height / 2
        w = width(mid)
        if w is None or w <= PINCH_FIT_M:
            return None
        for z in np.arange(mid + 0.005, fp.top - 0.01, 0.005):
            w = width(float(z))
            if w is not None and w <= PINCH_FIT_M:
                return float(z)
        return None

    def _pinch(self) -> Iterator[list[GraspPlan]]:
        for line in self.pinch_lines():
            yield from self.pinch_plans(line)

    def pinch_plans(self, line: PinchLine) -> Iterator[list[GraspPlan]]:
        """Pinches along ``line``: per palm direction and roll whose open hand dips no more than
        :data:`MAX_RAISE_M` into the table (raised clear of it), the group of its idle-finger variants; the hand's
        clearance of the objects is left to :meth:`hand_clear`."""
        a_w = line.axis
        down = np.array([0.0, 0.0, -1.0])
        for a_p in PINCH_AXES_PALM:
            shape = pinch_shape(self.hand, a_p, line.width, tips=line.low)
            if shape is None:
                continue
            n_p = np.array([0.0, -1.0, 0.0])  # palm normal, palm frame
            r0 = _frame(a_w, down) @ _frame(shape.axis, n_p).T  # pinch line onto a_w, palm facing down if it can
            for roll in PINCH_ROLLS_RAD:
                rot = axis_rotation(a_w, roll) @ r0
                normal = rot @ n_p
                if normal[2] > -0.2:
                    continue  # the palm must face the table to come from above
                palm = line.center - rot @ shape.center  # the width was rounded up: the pads centre on the line
                cover = self.hand.spheres(shape.open)
                dip = TABLE_CLEARANCE_M - float(np.min(self.table_gap(cover.centers @ rot.T + palm, cover.radii)))
                if dip > MAX_RAISE_M:
                    continue
                palm = palm + np.array([0.0, 0.0, max(dip + RAISE_MARGIN_M, 0.0)])
                group = []
                for rest in (TUCKED, STRAIGHT):
                    mid = {} if shape.middle else MIDDLE_TUCKED
                    open_hand = {"WRJ1": 0.0, "WRJ0": 0.0} | rest | mid | shape.open
                    close = rest | mid | self._squeezed(shape)
                    group.append(GraspPlan("pinch", pose_of(rot, palm), approach=down, approach_m=APPROACH_M,
                                           open_hand=open_hand, closing=((close, 14),),
                                           note=f"{line.note}, width {1000 * line.width:.0f} mm, palm axis {a_p}, "
                                                f"roll {roll:+.2f}"))
                yield group

    def _squeezed(self, shape: PinchShape) -> dict[str, float]:
        """``shape``'s closing joints; across an elongated object, the pinching fingers' lead over their touching
        joints scaled by :attr:`squeeze` (within joint limits)."""
        if self.squeeze == 1.0 or not self._elongated():
            return dict(shape.close)
        joints = actuated("th") + actuated("ff") + (actuated("mf") if shape.middle else ())
        lo, hi = self.hand.bounds(joints)
        lead = np.array([shape.close[j] - shape.contact[j] for j in joints])
        q = np.clip(np.array([shape.contact[j] for j in joints]) + self.squeeze * lead, lo, hi)
        return shape.close | dict(zip(joints, (float(v) for v in q), strict=True))

    def _tip(self) -> Iterator[list[GraspPlan]]:
        from gendex.solve.tip_pinch import TUCKED as TIP_REST
        from gendex.solve.tip_pinch import tip_candidates  # it builds on this module's pinch shapes

        prefer = np.array([np.cos(self.prefer), np.sin(self.prefer), 0.0])
        down = np.array([0.0, 0.0, -1.0])
        for _, rot, pos, shape, note in tip_candidates(self.hand, self.shape, self.table_z, prefer):
            yield [GraspPlan("tip", pose_of(rot, pos), approach=down, approach_m=APPROACH_M,
                             open_hand=TIP_REST | shape.open,
                             closing=tuple((TIP_REST | hand, 1) for hand in shape.closing), note=note)]


def squeeze_gain(mass_kg: float) -> float:
    """How much further than planned a pinch across an elongated object of ``mass_kg`` closes (see
    :data:`MAX_SQUEEZE_GAIN`)."""
    return float(np.clip(mass_kg / SQUEEZE_REF_KG, 1.0, MAX_SQUEEZE_GAIN))


def hand_fit_scale(size_xy_m: tuple[float, float], scale: float = 1.0) -> float:
    """The scale of an object of horizontal size ``size_xy_m`` (at scale 1) that fits the hand: ``scale`` when the
    object is then at most :data:`HAND_SPAN_M` wide across its narrow side, else the scale that makes it that wide."""
    narrow = min(size_xy_m)
    return scale if narrow * scale <= HAND_SPAN_M else HAND_SPAN_M / narrow


def object_heading(center_xy: np.ndarray, base_xy: np.ndarray) -> float:
    """Yaw (rad) from the robot base to an object: fingers pointing away from the base reach most easily."""
    return float(np.arctan2(center_xy[1] - base_xy[1], center_xy[0] - base_xy[0]))


__all__ = ["FINGERS", "GUARD_RAD", "HAND_SPAN_M", "OPEN_HAND", "RELEASE_HAND", "GraspPlan", "GraspSynthesizer",
           "PinchLine", "PinchShape", "axis_rotation", "hand_fit_scale", "headings", "object_heading", "palm_rotation",
           "pinch_shape", "pose_of", "squeeze_gain"]
