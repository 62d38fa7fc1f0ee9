"""Grasp synthesis over object geometry: shapes, finger kinematics, pinch lines, the kinematic check, physics trials."""

import numpy as np
import pytest
import sapien

from gendex.solve.grasp import TALL_M, GraspSynthesizer, object_heading, pinch_shape, squeeze_gain
from gendex.solve.grasp_trial import GraspTrials
from gendex.solve.hand import PAD_RADIUS_M, HandModel, actuated
from gendex.solve.ik import ArmIK
from gendex.solve.lift_check import LiftChecker, fitted_scale, lift_spec
from gendex.solve.shape import ObjectShape
from gendex_envs.task_env import TaskEnv


class Scene:
    """One object in a lift scene, with its shape, the hand model and a synthesizer."""

    def __init__(self, asset: str, seed: int = 3, scale: float = 1.0):
        self.env = TaskEnv(task_spec=lift_spec(asset, scale), control_mode="pd_joint_pos", obs_mode="none",
                           reward_mode="none")
        self.env.reset(seed=seed)
        self.ik = ArmIK(self.env.agent)
        self.hand = HandModel(self.ik, self.env.agent.robot)
        pose = self.env.obj("obj").pose
        m = sapien.Pose(pose.p[0].numpy(), pose.q[0].numpy()).to_transformation_matrix()
        self.shape = ObjectShape.of_actor(self.env.obj("obj")).posed(m)
        prefer = object_heading(self.shape.footprint().center, self.ik.base.p[:2])
        self.synth = GraspSynthesizer(self.hand, self.shape, 0.0, prefer)


@pytest.fixture(scope="module")
def bowl():
    s = Scene("bowl")
    yield s
    s.env.close()


@pytest.fixture(scope="module")
def golf():
    s = Scene("golf_ball")
    yield s
    s.env.close()


def test_pads_and_shared_samples_are_the_numbers_a_full_pass_gives(golf):
    """The solver's speed-ups change no number: a pad from the distal frames alone equals the one from every link's
    frame, and a hand model made later shares the first one's pad samples, equal to samples computed afresh."""
    from gendex.solve import hand as hand_mod

    h = golf.hand
    rng = np.random.default_rng(7)
    for _ in range(20):
        q = {j: float(rng.uniform(*h.bounds([j]))[0]) for f in ("th", "ff", "lf") for j in actuated(f)}
        _, frames = h._link_frames(q)
        full = np.array([frames[i][:3, :3] @ [0.0, 0.0, 0.016] + frames[i][:3, 3] for i in h._tips])
        assert np.array_equal(h.pads(q, 0.016), full)
    again = HandModel(golf.ik, golf.env.agent.robot)
    assert again._samples is h._samples and again._samples is hand_mod._SAMPLED[h._kinematics_key()]
    fresh = h._sample_pads()
    for key, (qs, tree) in fresh.items():
        assert np.array_equal(qs, h._samples[key][0]) and np.array_equal(tree.data, h._samples[key][1].data), key
    assert not h._samples["ff", 0.016][0].flags.writeable


def test_ray_intervals_match_a_face_by_face_reference(bowl):
    """Where the line is inside each convex part, merged: the fast loop against the plain definition."""
    rng = np.random.default_rng(3)
    shape = bowl.shape
    for _ in range(200):
        o = shape.vertices.mean(axis=0) + rng.normal(0, 0.05, 3)
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        spans = []
        for part in shape.parts:
            num, den = -(part.normals @ o + part.offsets), part.normals @ d
            with np.errstate(divide="ignore", invalid="ignore"):
                ts = num / den
            par = np.abs(den) < 1e-12
            if np.any(par & (num < 0)):
                continue
            lo, hi = np.max(ts[(den < 0) & ~par], initial=-np.inf), np.min(ts[(den > 0) & ~par], initial=np.inf)
            if lo < hi:
                spans.append((float(lo), float(hi)))
        merged = []
        for a, b in sorted(spans):
            if merged and a <= merged[-1][1] + 1e-6:
                merged[-1] = (merged[-1][0], max(merged[-1][1], b))
            else:
                merged.append((a, b))
        assert shape.ray_intervals(o, d) == merged


def test_rays_find_both_walls_of_a_bowl_and_one_solid_ball(bowl, golf):
    fp = bowl.shape.footprint()
    assert fp.length == pytest.approx(0.15, abs=0.005) and fp.height == pytest.approx(0.063, abs=0.003)
    origin = np.array([fp.center[0] - 0.2, fp.center[1], fp.bottom + 0.04])
    spans = bowl.shape.ray_intervals(origin, np.array([1.0, 0.0, 0.0]))
    assert len(spans) == 2  # the near wall and the far wall, the hollow between them
    assert all(0.002 < b - a < 0.015 for a, b in spans)
    gfp = golf.shape.footprint()
    spans = golf.shape.ray_intervals(np.array([gfp.center[0] - 0.2, gfp.center[1], gfp.bottom + 0.0215]),
                                     np.array([1.0, 0.0, 0.0]))
    assert len(spans) == 1 and spans[0][1] - spans[0][0] == pytest.approx(0.043, abs=0.002)
    # signed distance: inside negative, 5 cm above the top positive
    assert golf.shape.signed_distance(np.array([[*gfp.center, 0.02]]))[0] < 0
    assert golf.shape.signed_distance(np.array([[*gfp.center, gfp.top + 0.05]]))[0] == pytest.approx(0.05, abs=0.002)


def test_families_follow_the_shape(bowl, golf):
    assert golf.synth.families() == ["pinch"]  # too small for a power grasp
    assert bowl.synth.families() == ["pinch"]  # too wide for the hand: a wall pinch at the rim
    assert any("wall" in line.note for line in bowl.synth.pinch_lines())
    bottle = Scene("bottle")
    apple = Scene("apple")
    try:
        assert bottle.synth.families()[0] == "side" and apple.synth.families()[0] == "top"
    finally:
        bottle.env.close()
        apple.env.close()


def test_pinch_pads_land_on_the_contact_points(golf):
    line = golf.synth.pinch_lines()[0]
    plan = next(p for p in golf.synth.candidates() if p.kind == "pinch")
    axis_palm = tuple(float(v) for v in plan.note.split("palm axis (")[1].split(")")[0].split(", "))
    shape = pinch_shape(golf.hand, axis_palm, line.width)
    m = plan.palm.to_transformation_matrix()
    pads = golf.hand.pads(shape.contact) @ m[:3, :3].T + m[:3, 3]
    a = line.axis
    # the pinch was solved for the width rounded up to 5 mm: each pad within 2.5 mm (+ IK tolerance) of its contact
    assert np.linalg.norm(pads[0] - (line.thumb - PAD_RADIUS_M["th"] * a)) < 0.005
    assert np.linalg.norm(pads[1] - (line.finger + PAD_RADIUS_M["ff"] * a)) < 0.005
    normals = golf.hand.pad_normals(shape.contact) @ m[:3, :3].T
    assert normals[0] @ a > 0.3 and normals[1] @ -a > 0.3  # the pads face each other across the ball


def test_kinematic_check_rejects_a_hand_in_the_table_or_the_object(golf):
    plan = next(golf.synth.candidates())
    assert golf.synth.hand_clear(plan)
    import dataclasses

    low = dataclasses.replace(plan, palm=sapien.Pose(plan.palm.p - [0.0, 0.0, 0.03], plan.palm.q))
    assert not golf.synth.hand_clear(low)  # pads pushed 3 cm into the table
    inside = dataclasses.replace(plan, open_hand=plan.closed_hand, approach_m=0.0)
    assert not golf.synth.hand_clear(inside)  # the closing target lies inside the ball


def test_physics_trial_holds_a_good_grasp_and_rejects_a_bad_one(golf):
    trials = GraspTrials(golf.env)
    try:
        m_state = golf.env.get_state().clone()
        q0 = golf.env.agent.controller.target_qpos[0].numpy().astype(np.float64)
        from gendex.solve.motion import ArmHandMotion

        motion = ArmHandMotion(golf.env)
        held = None
        for plan in golf.synth.candidates():
            q_pre = motion.ik.solve(plan.pregrasp, motion.with_hand(q0, plan.open_hand), restarts=20,
                                    valid=motion.collision.is_free)
            if q_pre is None:
                continue
            held = trials.trial(plan, q_pre, "obj")
            if held.held:
                break
        assert held is not None and held.held and held.rise_m > 0.12
        # the same grasp 6 cm too high closes on air
        import dataclasses

        high = dataclasses.replace(held.plan, palm=sapien.Pose(held.plan.palm.p + [0.0, 0.0, 0.06], held.plan.palm.q))
        q_high = motion.ik.solve(high.pregrasp, q_pre, restarts=20)
        bad = trials.trial(high, q_high, "obj")
        assert not bad.held and bad.rise_m < 0.02 and "rose" in bad.why
        # trials never touch the env being solved
        assert torch_equal(golf.env.get_state(), m_state)
    finally:
        trials.close()


def lift_once(asset: str, seed: int):
    """One lift-and-hold attempt of ``asset`` (at the size a task holds it) on ``seed``."""
    checker = LiftChecker(asset)
    try:
        return checker(seed)
    finally:
        checker.close()


def torch_equal(a, b) -> bool:
    return bool((a == b).all())


@pytest.mark.parametrize("asset", ["bowl", *(pytest.param(a, marks=pytest.mark.slow)
                                             for a in ("dice", "spatula", "bowl_large"))])
def test_lift_and_hold_beyond_the_two_objects_the_old_grasp_knew(asset):
    """Each at the size a task holds it: the 22 cm bowl is fitted to the hand (scale ~0.41) as the generator does."""
    result = lift_once(asset, 1004)
    assert result.held, result.failure
    assert result.rise_m >= 0.10 and result.trials >= 1 and result.grasp.startswith("pinch")


def test_a_ball_wider_than_a_pinch_is_pinched_above_its_middle_and_held(golf):
    """The 96 mm softball is wider than the widest pinch at its middle: a pinch line is added where it is
    PINCH_FIT_M wide, above the middle (there the pads press it down into the hand), and that grasp holds. A ball
    that fits at its middle (the golf ball) gets no such line."""
    from gendex.solve import grasp

    s = Scene("softball")
    try:
        fp = s.shape.footprint()
        mid = fp.bottom + fp.height / 2
        lines = s.synth.pinch_lines()
        fitted = [ln for ln in lines if ln.center[2] > mid + 0.01 and ln.center[2] < fp.top - 0.02]
        assert fitted, [ln.note for ln in lines]
        assert all(ln.width <= grasp.PINCH_FIT_M + 0.002 for ln in fitted)
    finally:
        s.env.close()
    gfp = golf.shape.footprint()
    heights = {round(float(ln.center[2] - gfp.bottom), 3) for ln in golf.synth.pinch_lines()}
    assert heights == {round(gfp.height / 2, 3), round(gfp.height - 0.012, 3)}
    result = lift_once("softball", 1002)
    assert result.held and result.rise_m >= 0.10, result.failure


def test_a_pinch_raised_off_the_table_passes_its_own_clearance_check():
    """A pinch whose open hand would dip into the table is raised clear of it, and must then pass the clearance
    check: raised exactly to the table, rounding used to leave about half of them a hair below, and a marker lying
    across the robot's view had no pinch with the fingers pointing away from the robot (seed 1014: 0 reachable)."""
    s = Scene("marker", seed=1014)
    try:
        plans = [p for line in s.synth.pinch_lines() for group in s.synth.pinch_plans(line) for p in group]
        assert plans
        for p in plans:
            cover = s.hand.spheres(p.open_hand)
            m = p.palm.to_transformation_matrix()
            assert float(np.min(cover.centers @ m[2, :3] + m[2, 3] - cover.radii)) >= 0.0, p.note
        away = s.shape.footprint().center - s.ik.base.p[:2]
        away /= np.linalg.norm(away)
        pointing_away = [p for p in plans if s.synth.hand_clear(p)
                         and p.palm.to_transformation_matrix()[:2, 2] @ away > 0.5]
        assert pointing_away
    finally:
        s.env.close()


def test_distances_beside_a_thin_tilted_part_are_not_mistaken_for_contact():
    """Beside the edges of a fork handle's thin tilted segments, face planes alone put points at half their distance
    from the part (16 mm where it is 33 mm); the supporting planes along many directions keep the bound at 74-100 %
    of the exact distance (a small QP per part), and it stays a lower bound."""
    from scipy.optimize import minimize

    def exact(part, p):
        """Distance from p to the convex part: the nearest point inside all its face planes (a small QP)."""
        inside = {"type": "ineq", "fun": lambda x: -(part.normals @ x + part.offsets), "jac": lambda x: -part.normals}
        sol = minimize(lambda x: float((x - p) @ (x - p)), part.vertices.mean(axis=0), jac=lambda x: 2 * (x - p),
                       constraints=[inside], method="SLSQP", options={"ftol": 1e-14, "maxiter": 200})
        return float(np.linalg.norm(sol.x - p))

    s = Scene("fork", seed=1000)
    try:
        fp = s.shape.footprint()
        axis = np.array([fp.axis[0], fp.axis[1], 0.0])
        across = np.cross([0.0, 0.0, 1.0], axis)
        pts = np.array([fp.center[0], fp.center[1], 0.01]) + np.outer(np.linspace(0.02, 0.04, 5), across)
        pts = np.concatenate([pts + 0.03 * axis, pts - 0.03 * axis])
        d = s.shape.signed_distance(pts)
        truth = np.array([min(exact(part, p) for part in s.shape.parts) for p in pts])
        assert np.all(d <= truth + 1e-6) and np.all(d >= 0.7 * truth)  # measured: 0.74-1.0 of the truth
        faces_only = np.min([np.max(pts @ p.normals.T + p.offsets, axis=1) for p in s.shape.parts], axis=0)
        assert np.min(faces_only / truth) < 0.6  # what the faces alone said: down to 0.52
    finally:
        s.env.close()


def test_thin_objects_get_tip_pinches_only_where_friction_can_hold_them_off_the_table():
    """A knife's rounded handle (12 mm) is met just above its widest point: its pads press it down a little, within
    the friction cone, and it gets tip pinches near its centroid. Closed scissors (6 mm) are met only far above their
    widest point, where every pad would push them into the table: no tip pinch; nor has a wrench (7 mm) near its
    centroid (only across its open end, which the physics trials reject). A fork's handle arches off the table: its
    tip pinches are near its centroid, and their hands stay above the table and leave its top alone between the
    fingertips."""
    from gendex.solve import tip_pinch

    for asset, near in (("knife", True), ("scissors", False), ("wrench", False)):
        s = Scene(asset, seed=1000)
        try:
            assert s.synth.families() == ["pinch", "tip"]
            away = np.array([np.cos(s.synth.prefer), np.sin(s.synth.prefer), 0.0])
            lines = tip_pinch.table_lines(s.shape, 0.0, away)
            com = s.shape.centroid()[:2]
            central = [ln for ln in lines if np.linalg.norm((ln.thumb[:2] + ln.finger[:2]) / 2 - com) < 0.03]
            assert bool(central) == near, (asset, [ln.note for ln in lines])
            assert all(0.3 < line.press <= tip_pinch.MAX_PRESS for line in lines)  # knife: 0.40, pressed down
        finally:
            s.env.close()
    fork = Scene("fork", seed=1000)
    try:
        away = np.array([np.cos(fork.synth.prefer), np.sin(fork.synth.prefer), 0.0])
        lines = tip_pinch.table_lines(fork.shape, 0.0, away)
        assert lines and all(line.press <= tip_pinch.MAX_PRESS for line in lines)
        fp = fork.shape.footprint()
        along = float(abs((lines[0].thumb[:2] + lines[0].finger[:2]) / 2 - fork.shape.centroid()[:2]) @ fp.axis)
        assert along < 0.02
        plan = next(iter(fork.synth._tip()))[0]
        m = plan.palm.to_transformation_matrix()
        shapes = (plan.open_hand, *[targets for targets, _ in plan.closing])
        # every shape the hand passes through stays above the table; the last target is only the squeeze's lead
        # (SQUEEZE_GAIN times past the last shape: the guard stops the fingers on the fork long before it)
        for hand in shapes[:-1]:
            cover = fork.hand.spheres(hand)
            assert float(np.min(cover.centers @ m[2, :3] + m[2, 3] - cover.radii)) > 0.0
        assert fork.synth.hand_clear(plan)
    finally:
        fork.env.close()


@pytest.mark.parametrize("asset,seed", [("spoon", 1000), pytest.param("fork", 1000, marks=pytest.mark.slow),
                                        pytest.param("knife", 1000, marks=pytest.mark.slow)])
def test_a_utensil_lying_flat_is_lifted_by_a_fingertip_pinch_at_the_table(asset, seed):
    """Fork and spoon handles (1-2 mm strips arching off the table) and the knife's low handle held 0/20 before
    the tip pinch. The spoon's tip pinches often lift it between the index and the curled middle finger with the
    thumb off it, which does not count as held (seed 1001, 16 trials: 4 of them lifted it so, none with the thumb on
    it); on this seed the 12th trial holds it with thumb and index."""
    result = lift_once(asset, seed)
    assert result.held and result.rise_m >= 0.10, result.failure
    assert result.grasp.startswith("tip")


@pytest.mark.parametrize("asset,seed", [("knife", 10061), pytest.param("spoon", 10066, marks=pytest.mark.slow)])
def test_a_thin_object_is_held_once_its_contacts_are_solved_to_convergence(asset, seed):
    """At the scene's 15 contact-solver iterations none of the knife's 48 trials held it on seed 10061 (it turned
    out of the pads as it rose), and the spoon's 28th trial was the first to hold it on seed 10066. Thin objects'
    bodies are solved at THIN_SOLVER_ITERATIONS; both are lifted within a few trials (4 and 6)."""
    result = lift_once(asset, seed)
    assert result.held and result.rise_m >= 0.10, result.failure
    assert result.trials <= 12


def test_an_elongated_object_is_pinched_across_its_centroid_first():
    """The hammer's centre of mass lies 20 mm from its box's centre, towards the head; pinched there it twisted out
    of the pads (4/20). Its first pinch lines now cross its centroid."""
    s = Scene("hammer", seed=1000)
    try:
        fp = s.shape.footprint()
        s_com = float((s.shape.centroid()[:2] - fp.center) @ fp.axis)
        assert abs(s_com) > 0.015
        first = s.synth.pinch_lines()[0]
        assert abs(float((first.center[:2] - fp.center) @ fp.axis) - s_com) < 0.002
    finally:
        s.env.close()


def test_a_tall_object_is_pinched_level_with_its_centroid_first():
    """A can (12 cm tall) pinched 3 cm above the table turned about the pinch line as it rose and slid down the pads:
    on seed 10032 (the grasp record at 10020-10039) none of its ten trials held. Its first pinch lines now pass
    through its centroid's height, and it is lifted. A tall ball too wide to pinch at its middle (the softball at the
    size tasks give it) keeps the usual order: low first, then where it fits above its middle."""
    s = Scene("can", seed=1000)
    try:
        z_com = float(s.shape.centroid()[2])
        assert s.shape.footprint().height > TALL_M and z_com > 0.05
        first = s.synth.pinch_lines()[0]
        assert abs(float(first.center[2]) - z_com) < 1e-6
    finally:
        s.env.close()
    s = Scene("softball", seed=1000, scale=fitted_scale("softball"))
    try:
        fp, z_com = s.shape.footprint(), float(s.shape.centroid()[2])
        assert fp.height > TALL_M
        lines = s.synth.pinch_lines()
        assert abs(float(lines[0].center[2]) - (fp.bottom + 0.03)) < 1e-6  # the usual order: 3 cm up first
        assert all(abs(float(ln.center[2]) - z_com) > 0.005 for ln in lines)
    finally:
        s.env.close()
    result = lift_once("can", 10032)
    assert result.held and result.rise_m >= 0.10, result.failure
    assert result.grasp.startswith("pinch")


def test_a_heavy_object_is_pinched_harder_in_proportion_to_its_weight():
    """Across an elongated object (a hammer's handle) the pinching fingers' closing lead over the touching hand grows
    with the object's mass above 0.2 kg, at most twice (the guard stops the pads on the surface, so the lead is what
    sets how hard they press); a compact object (a can) keeps the planned lead whatever it weighs."""
    assert squeeze_gain(0.05) == squeeze_gain(0.2) == 1.0
    assert squeeze_gain(0.3) == pytest.approx(1.5) and squeeze_gain(0.42) == squeeze_gain(3.0) == 2.0
    for asset, elongated in (("hammer", True), ("can", False)):
        s = Scene(asset, seed=1000)
        try:
            prefer = object_heading(s.shape.footprint().center, s.ik.base.p[:2])
            heavy = GraspSynthesizer(s.hand, s.shape, 0.0, prefer, mass_kg=0.42)
            line = s.synth.pinch_lines()[0]
            light, firm = (next(synth.pinch_plans(line))[0] for synth in (s.synth, heavy))
            assert light.note == firm.note  # the same grasp, only closed harder
            assert np.allclose(light.palm.p, firm.palm.p) and np.allclose(light.palm.q, firm.palm.q)
            axis_palm = tuple(float(v) for v in light.note.split("palm axis (")[1].split(")")[0].split(", "))
            shape = pinch_shape(s.hand, axis_palm, line.width)
            assert shape.middle
            fingers = actuated("th") + actuated("ff") + actuated("mf")
            if not elongated:
                assert all(firm.closed_hand[j] == light.closed_hand[j] == shape.close[j] for j in fingers)
                continue
            lo, hi = s.hand.bounds(fingers)
            for j, low, high in zip(fingers, lo, hi, strict=True):
                assert light.closed_hand[j] == pytest.approx(shape.close[j])
                doubled = float(np.clip(shape.contact[j] + 2 * (shape.close[j] - shape.contact[j]), low, high))
                assert firm.closed_hand[j] == pytest.approx(doubled), (asset, j)
            assert any(abs(firm.closed_hand[j] - light.closed_hand[j]) > 0.1 for j in fingers)
        finally:
            s.env.close()


def test_a_hammer_pinched_hard_enough_for_its_weight_is_lifted():
    """Dev seed 781002: with the plain closing lead each of the ten pinches tried pressed its pads at 1-3 N and the
    hammer (0.42 kg) slid out as it rose: grasp_failed. Squeezed in proportion to its weight, it is lifted."""
    result = lift_once("hammer", 781002)
    assert result.held and result.rise_m >= 0.10, result.failure
    assert result.grasp.startswith("pinch")
