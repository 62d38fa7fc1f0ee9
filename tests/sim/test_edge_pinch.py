"""Flat ringed tools (closed scissors, a ring wrench) are dragged by the ring to the table's side edge, and hooked on
the index through the ring or pinched across the overhang (``gendex/solve/edge_pinch.py``)."""

from __future__ import annotations

import re

import numpy as np
import pytest
import sapien

from gendex.solve.edge_drag import HINGE_OVERHANG_M, HOOK_MIN_RADIUS_M, OVERHANG_M
from gendex.solve.edge_geometry import find_ring
from gendex.solve.edge_trial import VARIANTS
from gendex.solve.hand import PAD_RADIUS_M
from gendex.solve.lift_check import LiftChecker, lift_spec
from gendex.solve.shape import ObjectShape
from gendex_envs.task_env import TaskEnv


def _ring_in_object_frame(asset: str, scale: float = 1.0, seed: int = 5) -> np.ndarray | None:
    env = TaskEnv(task_spec=lift_spec(asset, scale), obs_mode="none", reward_mode="none")
    try:
        env.reset(seed=seed)
        p = env.obj("obj").pose
        pose = sapien.Pose(p.p[0].numpy(), p.q[0].numpy())
        ring = find_ring(ObjectShape.of_actor(env.obj("obj")).posed(pose.to_transformation_matrix()))
        return None if ring is None else (pose.inv() * sapien.Pose(ring)).p
    finally:
        env.close()


@pytest.mark.parametrize("asset,where", [("scissors", [(-0.0685, 0.019), (-0.0685, -0.019)]),
                                         ("wrench", [(-0.078, 0.0)])])
def test_a_finger_ring_is_found_from_the_hull_cover(asset, where):
    """The scissors' finger rings (20 mm holes) and the wrench's ring end (15 mm, 6.9 mm to its octagon's flats)
    are where their build script puts them (its frame re-centred on the footprint), whatever the object's pose."""
    ring = _ring_in_object_frame(asset)
    assert ring is not None
    assert min(np.linalg.norm(ring[:2] - np.asarray(w)) for w in where) < 0.003, ring


@pytest.mark.parametrize("asset,scale", [("knife", 1.0), ("fork", 1.0), ("spatula", 1.0), ("plate", 0.405),
                                         ("apple", 1.0)])
def test_no_ring_in_objects_without_one(asset, scale):
    """A fork's tines and a spatula's slot are open on one side; a plate at task size is flat but solid."""
    assert _ring_in_object_frame(asset, scale) is None


def test_closed_scissors_are_hooked_through_a_ring_at_the_edge():
    """No grasp of closed scissors (6 mm tall) held in a physics trial on any seed of the grasp records (0/20
    each). Seed 785026 (a dev seed of the hook): dragged by a ring to the table's side edge, the index through the ring
    and curled, the tool lifted hanging from it with the thumb on the ring, and held."""
    checker = LiftChecker("scissors")
    try:
        result = checker(785026)
        y = float(checker.env.obj("obj").pose.p[0, 1])
    finally:
        checker.close()
    assert result.held and result.rise_m >= 0.10, result.failure
    assert result.grasp.startswith("edge grasp (hook"), result.grasp
    assert abs(y) > 0.5  # at the side edge (0.6 m from the centre line), not where it lay (|y| < 0.22)


@pytest.mark.parametrize("asset,hooked", [("scissors", True), ("wrench", False)])
def test_only_a_ring_the_finger_passes_through_is_hooked(asset, hooked):
    """The scissors' holes (8.6-8.8 mm to their walls) let the index's end (7.1 mm) through; the wrench's (6.9 mm)
    does not, and it is pinched instead."""
    env = TaskEnv(task_spec=lift_spec(asset), obs_mode="none", reward_mode="none")
    try:
        env.reset(seed=5)
        p = env.obj("obj").pose
        shape = ObjectShape.of_actor(env.obj("obj")).posed(
            sapien.Pose(p.p[0].numpy(), p.q[0].numpy()).to_transformation_matrix())
        ring = find_ring(shape)
        hole = float(shape.signed_distance(ring[None])[0])
    finally:
        env.close()
    assert (hole >= HOOK_MIN_RADIUS_M) == hooked, hole
    assert hole > PAD_RADIUS_M["ff"] if hooked else hole < PAD_RADIUS_M["ff"]


@pytest.mark.slow
def test_the_wrench_is_tried_five_ways_and_hinged_across_its_ring_past_the_edge():
    """The wrench (0.15 kg, its weight 7.7 cm from the ring) slipped out of the clamp across its ring's far side in
    most attempts; it is pinched across the ring level with it instead, the pads below the table top past its edge,
    and stood up on its far end as it rises. Dev seed 788000: in its physics trial the first of the edge grasp's ways
    failed and a later one held (the second, the same edge 10 cm nearer the robot; with OpenBLAS's AVX-512 kernels it
    was the fifth), and the robot did the way that held and held the tool. The ring was dragged further past the edge
    than the 2 cm that let the hinge twist out (``HINGE_OVERHANG_M``; the centre of mass stays ``COM_INSIDE_M``
    inside). (The hinge's earlier dev seeds, 784051, 786011 and 787002, fail in the rebuilt scenes the benchmark now
    uses: no way held in a trial.)"""
    checker = LiftChecker("wrench")
    try:
        result = checker(788000)
        edge = [t for t in checker.executor.rigid.trial_log if t.plan is None or t.plan.kind == "edge"]
    finally:
        checker.close()
    assert result.held and result.rise_m >= 0.10, result.failure
    chosen = len(edge) - 1  # the trials stop at the first way that held
    assert 1 <= chosen < len(VARIANTS) and [t.held for t in edge] == [False] * chosen + [True], edge
    assert "hinge" in result.grasp and f"dragged to {VARIANTS[chosen]})" in result.grasp, result.grasp
    assert result.forecast
    past_mm = int(re.search(r"ring (\d+) mm past the edge", result.grasp).group(1))
    assert 1000 * OVERHANG_M + 10 <= past_mm <= 1000 * HINGE_OVERHANG_M + 10, result.grasp


def _lift_wrench(seed: int):
    """The lift-and-hold attempt of the wrench on ``seed``, in a checker of its own."""
    checker = LiftChecker("wrench")
    try:
        return checker(seed)
    finally:
        checker.close()


@pytest.mark.slow
def test_a_wrench_lying_along_the_edge_is_turned_before_the_drag():
    """Dev seed 787003: the wrench lies along the side edge it is dragged to. The wedged finger keeps the tool's heading
    while it drags, so it reached the edge lying along it and went over it whole. Turned first by the hand about the
    finger in its ring, it reaches the edge ring first and is hinged there and held."""
    result = _lift_wrench(787003)
    assert result.held and result.rise_m >= 0.10, result.failure
    assert "hinge" in result.grasp, result.grasp
