"""Fingertip pinch at the table: a grasp family for thin objects lying flat (a fork, a spoon, a spatula).

An object only a centimetre or so tall is lower than the ShadowHand's fingertips are wide: the distal capsules have
7.1 mm (fingers) and 9.2 mm (thumb) radius, so a pad centre is at least that high when its fingertip touches the table.
A pad pushes along the line from its centre to the contact point; a contact below the centre presses the object into
the table as well as squeezing it, and friction holds the object up only while that push is less steep than the
friction cone (the tangent of its angle below the horizontal under the pad-object friction). So this family squeezes
where the pads push at most :data:`MAX_PRESS` down: an arched handle (fork, spoon: they push up), a thick rounded
handle (a knife's, met just above its widest point), a raised edge. Flatter objects (closed scissors, 6 mm; a wrench,
7 mm) have no such line and are left to the other families.

1. **Where** (:func:`table_lines`). On lines across the object's long axis (or through a compact object's centre at
   several headings), a thumb pad and an index pad are slid in horizontally at the height where their fingertips just
   clear the table (:data:`LIFT_M` above it), and :func:`touch` finds where each first meets material and the
   direction it then pushes. A line is kept when neither pad presses down more than :data:`MAX_PRESS` (the vertical
   component of the unit push) and the pads' centres are at most :data:`MAX_WIDTH_M` apart; lines are ordered by
   that press and by their distance from the object's centroid (the centre of mass of a uniform object).
2. **Hand** (:func:`solve_tip_shape`). For a few palm orientations about the line, the palm pose and the thumb and
   index joints are solved together (least squares) so that both fingertips' end caps sit on their pad centres and
   every sphere of the hand stays :data:`MARGIN_M` above the table. The same fingertip targets slid out along the
   line (the pre-shape) and in (the squeeze) give the closing path: hand shapes a control step apart along which
   both fingertips travel level with the table, so neither digs into it nor rides up onto the object. Solutions are
   cached by the pads' relative position, so an object seen again costs nothing.
3. The candidates are :class:`~gendex.solve.grasp.GraspPlan` of kind ``tip``; the synthesizer checks the open hand's
   approach from above like any other, and physics trials rank them.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from gendex.solve.grasp import ELONGATED
from gendex.solve.hand import DIFF_STEP, PAD_RADIUS_M, HandModel, actuated
from gendex.solve.shape import PosedShape

LIFT_M = 0.001
"""Each fingertip's lowest point this far above the table while it closes."""
MARGIN_M = 0.001
"""Every sphere of the hand at least this far above the table (the fingertips' own ones included)."""
MAX_PRESS = 0.45
"""Largest downward component of a pad's unit push on the object for a line to be kept (0: horizontal; 0.45 is 27°
below it, tangent 0.50). PhysX averages the two materials' frictions: a pad's 1.0 (the scene's default) with a
catalog object's 0.6 gives 0.8, a cone of 39°, so 0.45 leaves room for dynamic friction and uneven squeezes. Measured
(lift check, dev seeds 1000-1002): the knife's handle, met at 0.40, held 3/3 (at 0.3 it had no line and held 0/20 in
the benchmark); the scissors' best line (0.69) held 0/2, the wrench's near its centroid (0.60) 0/2, and those kept
at 0.45, across the wrench's open end 66 mm from its centroid (0.43), 0/3."""
MAX_WIDTH_M = 0.075
"""Farthest apart the thumb and index pad centres may be at first touch."""
OPEN_M = {"th": (0.016, 0.005), "ff": (0.008, 0.002)}
"""Pre-shape: each fingertip this far outside its first touch along the line, and this far up (the thumb opens
farther: the index's tip, with three joints, cannot also slide far along the table). Closing, each comes down to
the table and slides the last :data:`LEVEL_M` level with it."""
LEVEL_M = 0.006
SQUEEZE_M = 0.006
"""Closing target: each fingertip this far past its first touch (the guard stops it on the surface)."""
SQUEEZE_GAIN = 6.0
"""The last closing target carries the squeeze on this many times as far in joint space: the fingers stop on the
object, and the target's lead sets how hard they press (a 6 mm squeeze left about 1 N a pad, too little to hold)."""
PATH_STEPS = 8
"""Hand shapes between the pre-shape and first touch (one control step each); half as many more into the squeeze."""
AXES_PALM = ((-0.43, 0.25, 0.87), (-0.25, 0.43, 0.87), (-0.5, 0.0, 0.87), (0.0, 0.5, 0.87))
"""Palm-frame directions of the line from the thumb's tip to the index's (the pinch directions of
:data:`gendex.solve.grasp.PINCH_AXES_PALM`) the hand solve starts from."""
ROLLS_RAD = (-0.35, -0.7, 0.0, 0.35, 0.7)
"""Palm orientations about the line the hand solve starts from."""
WIDTH_STEP_MM = 4
"""Tip pinches are solved for widths in these steps; an object up to this much narrower is met during the squeeze."""
ALONG_STEP_M = 0.005
"""Spacing of the candidate lines along an elongated object."""
MAX_IK_ERR_M = 0.002
"""A hand solution counts when both fingertips are within this of their targets and no sphere dips into the table by
more than :data:`MAX_DIP_M`."""
MAX_DIP_M = 0.0005
SOLVE_EVALS = 60
"""Least-squares iterations a hand solve may take (those that converge take 10-30)."""
BAND_TOL_M = 0.001
"""A sphere counts as reaching over the object when it overlaps the span between the fingertips' pads by more than
this (the fingertips' own end caps just touch its edges)."""
HEIGHT_STEP_M = 0.002
"""Tip pinches are solved for object heights in these steps (rounded up)."""

TUCKED = {"MFJ3": 0.0, "MFJ2": 1.4, "MFJ1": 1.2, "RFJ3": 0.0, "RFJ2": 1.4, "RFJ1": 1.2, "LFJ4": 0.0, "LFJ3": 0.0,
          "LFJ2": 1.4, "LFJ1": 1.2, "WRJ1": 0.0, "WRJ0": 0.0}
"""The fingers a tip pinch does not use, curled out of the way, and the hand wrist straight."""
STARTS = ("pinch", "opposed")
"""Where hand solves start (see :func:`tip_shape`)."""
INIT_HAND = {"THJ4": 0.6, "THJ3": 1.0, "THJ2": 0.0, "THJ1": 0.3, "THJ0": -0.3, "FFJ3": 0.0, "FFJ2": 0.8, "FFJ1": 0.6}
"""Thumb and index opposed half-way through their ranges: where a hand solve starts when no pinch of the width is
known (:func:`gendex.solve.grasp.pinch_shape`)."""
_UP = np.array([0.0, 0.0, 1.0])


# ---------------------------------------------------------------------------------------------- where
def touch(shape: PosedShape, center: np.ndarray, line: np.ndarray, side: int, height: float, radius: float,
          axis: np.ndarray, samples: int = 21) -> tuple[float, np.ndarray] | None:
    """Where a sphere of ``radius`` whose centre slides at ``height`` along ``center + t * line`` (``line`` a
    horizontal unit vector) first meets the object, coming from ``t = +inf`` (``side`` +1) or ``-inf`` (-1).

    Returns the centre's ``t`` at first touch and the unit push the sphere then gives the object (from its centre
    towards the contact point; a positive z component presses the object down), or None when the line misses it.
    The sphere is sampled as horizontal chords at ``samples`` heights in a few vertical planes beside the line
    (``axis``: the horizontal direction across it); each chord meets material where a horizontal ray does.
    """
    best: tuple[float, float, float, float] | None = None
    for frac in (0.0, -0.5, 0.5, -0.85, 0.85):
        r = radius * math.sqrt(1.0 - frac * frac)
        base = center + frac * radius * axis
        for dz in np.linspace(-r, r, samples):
            z = height + dz
            if z <= 1e-4:
                continue
            spans = shape.ray_intervals(np.array([base[0], base[1], z]), line)
            if not spans:
                continue
            edge = spans[-1][1] if side > 0 else spans[0][0]
            half = math.sqrt(max(r * r - dz * dz, 0.0))
            t = edge + side * half
            if best is None or side * (t - best[0]) > 0:
                best = (t, edge, z, frac * radius)
    if best is None:
        return None
    t, edge, z, lateral = best
    push = np.array([edge - t, lateral, z - height])  # (along line, across, up): centre -> contact
    push /= max(float(np.linalg.norm(push)), 1e-12)
    world = push[0] * line + push[1] * axis + np.array([0.0, 0.0, push[2]])
    return t, world


@dataclass(frozen=True)
class TipLine:
    """Where a tip pinch squeezes: the thumb's and the index's fingertip end-cap centres at first touch (world),
    the horizontal unit direction from the thumb to the index, and how hard each pad would press the object down."""

    thumb: np.ndarray
    finger: np.ndarray
    direction: np.ndarray
    press: float
    """The larger of the two pads' downward push components (see :func:`touch`)."""
    note: str

    @property
    def width(self) -> float:
        return float(np.linalg.norm((self.finger - self.thumb)[:2]))


def table_lines(shape: PosedShape, table_z: float, prefer_dir: np.ndarray) -> list[TipLine]:
    """Candidate tip-pinch lines of ``shape`` (see the module docstring), best first; ``prefer_dir``: the horizontal
    direction fingers reach most easily (away from the robot), to break ties."""
    fp = shape.footprint()
    com = shape.centroid()
    axis = np.array([fp.axis[0], fp.axis[1], 0.0])
    h_t = table_z + PAD_RADIUS_M["th"] + LIFT_M
    h_f = table_z + PAD_RADIUS_M["ff"] + LIFT_M
    center = np.array([fp.center[0], fp.center[1], 0.0])
    if fp.length > ELONGATED * fp.width:
        s_com = float((com[:2] - fp.center) @ fp.axis)
        half = fp.length / 2 - 0.01
        spots = [(s, np.cross(_UP, axis)) for s in np.arange(-half, half + 1e-9, ALONG_STEP_M)]
        spots = [(float(s), d) for s, d in spots]
    else:
        s_com = 0.0
        spots = [(0.0, np.array([math.cos(y), math.sin(y), 0.0])) for y in np.linspace(0, math.pi, 8, endpoint=False)]
    lines = []
    for s, across in spots:
        c = center + s * axis
        side_dir = np.cross(_UP, across)
        for d in (across, -across):
            t_hit = touch(shape, c, d, -1, h_t, PAD_RADIUS_M["th"], side_dir)
            f_hit = touch(shape, c, d, +1, h_f, PAD_RADIUS_M["ff"], side_dir)
            if t_hit is None or f_hit is None:
                continue
            press = max(-float(t_hit[1][2]), -float(f_hit[1][2]))
            thumb = c + t_hit[0] * d + [0.0, 0.0, h_t]
            finger = c + f_hit[0] * d + [0.0, 0.0, h_f]
            width = float(np.linalg.norm((finger - thumb)[:2]))
            if press > MAX_PRESS or width > MAX_WIDTH_M:
                continue
            note = f"{1000 * (s - s_com):+.0f} mm from the centroid, press {press:+.2f}, width {1000 * width:.0f} mm"
            lines.append((press + 2.0 * abs(s - s_com) / max(fp.length, 1e-6) - 0.05 * float(d @ prefer_dir),
                          TipLine(thumb, finger, d, press, note)))
    lines.sort(key=lambda sl: sl[0])
    return [line for _, line in lines]


# ---------------------------------------------------------------------------------------------- hand
@dataclass(frozen=True)
class TipShape:
    """A tip pinch in the line frame (x from the thumb's tip to the index's, z up, origin at the thumb's tip at
    first touch): the palm pose and the hand shapes of the pre-shape, first touch and closing path."""

    rot: np.ndarray
    """[3, 3] palm rotation."""
    pos: np.ndarray
    """[3] palm origin."""
    open: dict[str, float]
    contact: dict[str, float]
    closing: tuple[dict[str, float], ...]
    """Hand shapes from just inside the pre-shape to the squeeze, one control step apart."""


class _Fingers:
    """Fingertip kinematics with the table as a constraint, for one hand (module-level cache by hand)."""

    def __init__(self, hand: HandModel):
        self.hand = hand
        self.th, self.ff = actuated("th"), actuated("ff")
        # the direction each pad faces, in its distal link's frame (constant: the last joint turns about a fixed axis)
        mid = {j: 0.5 * (lo + hi) for j, lo, hi in zip(self.th + self.ff, *hand.bounds(self.th + self.ff),
                                                        strict=True)}
        pose = hand.pose(mid)
        normals = hand.pad_normals(mid)
        self.face = {f: pose.distal[k].T @ normals[k] for k, f in ((0, "th"), (1, "ff"))}
        self._owner = pose.cover.owner
        self._groups = (self._owner == "th", self._owner == "ff", ~np.isin(self._owner, ("th", "ff")))

    def residual_terms(self, joints: dict[str, float], rot: np.ndarray, pos: np.ndarray, floor: float, top: float
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(fingertip end caps [2, 3], pad facing directions [2, 3], clearances [S]) with the palm at ``rot``,
        ``pos`` (line frame). A sphere's clearance is its height above ``floor`` (the table), and for a sphere that
        overlaps the object's span between the fingertips (anything but the two fingertips themselves), its height
        above ``top`` (the object's top) as well: nothing reaches over the object lower than that."""
        pose = self.hand.pose(joints)
        tips = pose.tips[:2] @ rot.T + pos
        faces = np.array([rot @ pose.distal[0] @ self.face["th"], rot @ pose.distal[1] @ self.face["ff"]])
        centers = pose.cover.centers @ rot.T + pos
        radii = pose.cover.radii
        bottom = centers[:, 2] - radii
        lo_x = tips[0, 0] + PAD_RADIUS_M["th"] + BAND_TOL_M
        hi_x = tips[1, 0] - PAD_RADIUS_M["ff"] - BAND_TOL_M
        over = (centers[:, 0] + radii > lo_x) & (centers[:, 0] - radii < hi_x)
        clear = np.minimum(bottom - floor, np.where(over, bottom - top, np.inf))
        return tips, faces, clear

    def violations(self, clear: np.ndarray) -> np.ndarray:
        """[G] how far each group of spheres (thumb, index, the rest) dips below its clearance (root sum of squares,
        weighted): a few residuals instead of one per sphere keep the least-squares steps cheap."""
        dip = np.minimum(clear - MARGIN_M, 0.0)
        return 3.0 * np.array([np.linalg.norm(dip[group]) for group in self._groups])

    def solve(self, a_palm: tuple[float, float, float], roll: float, finger_at: np.ndarray, floor: float,
              top: float, init: tuple[np.ndarray, dict[str, float]]
              ) -> tuple[np.ndarray, np.ndarray, dict[str, float], dict[str, float]] | None:
        """Palm pose and the thumb/index joints of first touch (the thumb's tip at the origin, the index's at
        ``finger_at``, line frame) and of the pre-shape (each tip :data:`OPEN_M` outside and up), every sphere
        above ``floor`` and none over the object lower than ``top`` in both; from the pinch ``init`` (palm-frame
        centre, joints). Solving both shapes with one palm keeps the fingers clear of their joint limits where they
        must open."""
        from gendex.solve.grasp import _frame, axis_rotation

        hand, th, ff = self.hand, self.th, self.ff
        n = len(th + ff)
        x_dir = np.array([1.0, 0.0, 0.0])
        a_p = np.asarray(a_palm, float) / np.linalg.norm(a_palm)
        r0 = axis_rotation(x_dir, roll) @ _frame(x_dir, -_UP) @ _frame(a_p, np.array([0.0, -1.0, 0.0])).T
        c_p, joints0 = init
        p0 = finger_at / 2 - r0 @ c_p
        lo_j, hi_j = hand.bounds(th + ff)
        q0 = np.clip([joints0[j] for j in th + ff], lo_j + 1e-6, hi_j - 1e-6)
        x0 = np.concatenate([np.zeros(3), p0, q0, q0])
        lo = np.concatenate([-np.ones(3), p0 - 0.2, lo_j, lo_j])
        hi = np.concatenate([np.ones(3), p0 + 0.2, hi_j, hi_j])
        (t_out, t_up), (f_out, f_up) = OPEN_M["th"], OPEN_M["ff"]
        touching = np.array([np.zeros(3), finger_at])
        opened = np.array([[-t_out, 0.0, t_up], finger_at + [f_out, 0.0, f_up]])

        def unpack(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, dict[str, float], dict[str, float]]:
            rot = Rotation.from_rotvec(x[:3]).as_matrix() @ r0
            return (rot, x[3:6], TUCKED | dict(zip(th + ff, (float(v) for v in x[6:6 + n]), strict=True)),
                    TUCKED | dict(zip(th + ff, (float(v) for v in x[6 + n:]), strict=True)))

        def residual(x: np.ndarray) -> np.ndarray:
            rot, pos, contact, open_ = unpack(x)
            tips, faces, heights = self.residual_terms(contact, rot, pos, floor, top)
            tips_o, _, heights_o = self.residual_terms(open_, rot, pos, floor, top)
            facing = [0.02 * (faces[0] @ x_dir - 1.0), 0.02 * (-faces[1] @ x_dir - 1.0)]
            return np.concatenate([(tips - touching).ravel(), (tips_o - opened).ravel(),
                                   self.violations(heights), self.violations(heights_o), facing])

        sol = least_squares(residual, x0, bounds=(lo, hi), diff_step=DIFF_STEP, max_nfev=SOLVE_EVALS, ftol=1e-6,
                            xtol=1e-6)
        rot, pos, contact, open_ = unpack(sol.x)
        tips, _, heights = self.residual_terms(contact, rot, pos, floor, top)
        tips_o, _, heights_o = self.residual_terms(open_, rot, pos, floor, top)
        err = max(np.linalg.norm(tips - touching, axis=1).max(), np.linalg.norm(tips_o - opened, axis=1).max())
        if err > MAX_IK_ERR_M or min(heights.min(), heights_o.min()) < MARGIN_M - MAX_DIP_M:
            return None
        return rot, pos, contact, open_

    def slide(self, finger: str, rot: np.ndarray, pos: np.ndarray, joints: dict[str, float], points: np.ndarray,
              floor: float, top: float, towards: dict[str, float] | None = None) -> list[dict[str, float]] | None:
        """Joints of ``finger`` putting its tip on each of ``points`` [n, 3] in turn (line frame) with the palm fixed,
        each solved from the one before moved a step towards ``towards`` (the path's known end, if any); None when a
        point is out of reach or would dip a sphere into the table."""
        hand = self.hand
        js = self.th if finger == "th" else self.ff
        k_tip = ("th", "ff").index(finger)
        lo, hi = hand.bounds(js)
        out, prev = [], dict(joints)
        for target in points:

            def residual(x: np.ndarray, target: np.ndarray = target, prev: dict[str, float] = prev) -> np.ndarray:
                q = prev | dict(zip(js, (float(v) for v in x), strict=True))
                tips, _, clear = self.residual_terms(q, rot, pos, floor, top)
                mine = self._owner == finger
                return np.concatenate([tips[k_tip] - target, [3.0 * np.linalg.norm(np.minimum(clear[mine] - MARGIN_M,
                                                                                              0.0))]])

            x0 = np.array([prev[j] for j in js])
            if towards is not None:
                x0 = x0 + (np.array([towards[j] for j in js]) - x0) / max(len(points) - len(out), 1)
            x0 = np.clip(x0, lo + 1e-6, hi - 1e-6)
            sol = least_squares(residual, x0, bounds=(lo, hi), diff_step=DIFF_STEP, max_nfev=30, ftol=1e-6, xtol=1e-6)
            res = residual(sol.x)
            if np.linalg.norm(res[:3]) > MAX_IK_ERR_M or res[3] > 3.0 * MAX_DIP_M:
                return None
            prev = prev | dict(zip(js, (float(v) for v in sol.x), strict=True))
            out.append({j: prev[j] for j in js})
        return out


_FINGERS: dict[int, _Fingers] = {}


def _fingers(hand: HandModel) -> _Fingers:
    if id(hand) not in _FINGERS:
        _FINGERS[id(hand)] = _Fingers(hand)
    return _FINGERS[id(hand)]


@functools.lru_cache(maxsize=256)
def _tip_shape_cached(hand_id: int, a_palm: tuple[float, float, float], roll: float, width_mm: int,
                      height_mm: int, start: str) -> TipShape | None:
    from gendex.solve.grasp import pinch_shape

    hand = _HANDS[hand_id]
    fingers = _fingers(hand)
    width = width_mm / 1000.0
    finger_at = np.array([width, 0.0, PAD_RADIUS_M["ff"] - PAD_RADIUS_M["th"]])
    floor = -(PAD_RADIUS_M["th"] + LIFT_M)  # the table, seen from the thumb's tip centre
    top = floor + height_mm / 1000.0 + MARGIN_M
    if start == "pinch":
        pinch = pinch_shape(hand, a_palm, width - PAD_RADIUS_M["th"] - PAD_RADIUS_M["ff"], tips=True)
        if pinch is None:
            return None
        init = (pinch.center, pinch.contact)
    else:
        pose = hand.pose(INIT_HAND)
        init = ((pose.tips[0] + pose.tips[1]) / 2, INIT_HAND)
    solved = fingers.solve(a_palm, roll, finger_at, floor, top, init)
    if solved is None:
        return None
    rot, pos, contact, open_ = solved
    n_in = PATH_STEPS // 2
    paths = {}
    for f, start, sign in (("th", np.zeros(3), -1.0), ("ff", finger_at, 1.0)):
        into = fingers.slide(f, rot, pos, contact, start + np.outer(np.arange(1, n_in + 1) / n_in,
                                                                      [-sign * SQUEEZE_M, 0.0, 0.0]), floor, top)
        d_out, d_up = OPEN_M[f]
        out = fingers.slide(f, rot, pos, contact, start + _open_path(sign * d_out, d_up), floor, top, towards=open_)
        if out is None or into is None:
            return None
        paths[f] = (out, into)
    rest = {j: v for j, v in contact.items() if j not in fingers.th + fingers.ff}
    shapes_out = [rest | paths["th"][0][k] | paths["ff"][0][k] for k in range(PATH_STEPS)]
    shapes_in = [rest | paths["th"][1][k] | paths["ff"][1][k] for k in range(n_in)]
    lo, hi = hand.bounds(fingers.th + fingers.ff)
    press = {j: float(np.clip(contact[j] + SQUEEZE_GAIN * (shapes_in[-1][j] - contact[j]), a, b))
             for j, a, b in zip(fingers.th + fingers.ff, lo, hi, strict=True)}
    closing = (*reversed(shapes_out[:-1]), contact, *shapes_in, rest | press)
    return TipShape(rot, pos, shapes_out[-1], contact, closing)


_HANDS: dict[int, HandModel] = {}


def _open_path(out: float, up: float) -> np.ndarray:
    """[PATH_STEPS, 3] fingertip offsets from first touch to the pre-shape ``out`` along the line and ``up``: level
    for the first :data:`LEVEL_M`, then straight to the pre-shape."""
    level = math.copysign(min(LEVEL_M, abs(out)), out)
    corner = np.array([level, 0.0, 0.0])
    end = np.array([out, 0.0, up])
    n_level = max(1, round(PATH_STEPS * abs(level) / (abs(level) + float(np.linalg.norm(end - corner)) + 1e-9)))
    first = np.outer(np.arange(1, n_level + 1) / n_level, corner)
    rest = corner + np.outer(np.arange(1, PATH_STEPS - n_level + 1) / (PATH_STEPS - n_level), end - corner)
    return np.vstack([first, rest])


def tip_shape(hand: HandModel, a_palm: tuple[float, float, float], roll: float, width_m: float, height_m: float,
              start: str = "pinch") -> TipShape | None:
    """The tip pinch whose fingertips' centres are ``width_m`` apart at first touch, rounded up to
    :data:`WIDTH_STEP_MM` (the closing path squeezes farther than that), of an object ``height_m`` tall (rounded up
    to :data:`HEIGHT_STEP_M`), from palm direction ``a_palm`` and ``roll`` (cached). The hand solve starts from the
    pinch of that width (``start="pinch"``, :func:`gendex.solve.grasp.pinch_shape`) or from :data:`INIT_HAND`
    (``"opposed"``): the two find different hands, and trials tell which hold."""
    _HANDS[id(hand)] = hand
    step = WIDTH_STEP_MM
    h_step = round(HEIGHT_STEP_M * 1000)
    return _tip_shape_cached(id(hand), tuple(a_palm), float(roll), int(step * math.ceil(width_m * 1000 / step)),
                             int(h_step * math.ceil(height_m * 1000 / h_step)), start)


def line_frame(line: TipLine) -> np.ndarray:
    """[3, 3] rotation from the line frame (x: thumb to index, z up) to the world."""
    x = np.array([line.direction[0], line.direction[1], 0.0])
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(_UP, x), _UP])


def tip_candidates(hand: HandModel, shape: PosedShape, table_z: float, prefer_dir: np.ndarray,
                   max_lines: int = 6) -> Iterator[tuple[TipLine, np.ndarray, np.ndarray, TipShape, str]]:
    """(line, palm rotation, palm position (world), hand shapes, note) of the tip pinches of ``shape``, best lines
    first; each hand is centred on its line (an object narrower than the solved width meets both fingertips a little
    inside their first-touch points)."""
    height = shape.footprint().top - table_z
    for line in table_lines(shape, table_z, prefer_dir)[:max_lines]:
        frame = line_frame(line)
        for start, a_palm, roll in itertools.product(STARTS, AXES_PALM, ROLLS_RAD):
            solved = tip_shape(hand, a_palm, roll, line.width, height, start)
            if solved is None:
                continue
            width = WIDTH_STEP_MM * math.ceil(line.width * 1000 / WIDTH_STEP_MM) / 1000.0
            origin = line.thumb - (width - line.width) / 2 * frame[:, 0]
            yield (line, frame @ solved.rot, origin + frame @ solved.pos, solved,
                   f"{line.note}, palm axis {a_palm}, roll {roll:+.2f}, from the {start} hand")


__all__ = ["TipLine", "TipShape", "line_frame", "table_lines", "tip_candidates", "tip_shape", "touch"]
