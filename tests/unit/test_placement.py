"""Collision-free reset layouts (gendex_envs.placement) and typed failure reasons (gendex.solve.failure)."""

import math
import pickle

import pytest
import torch

from gendex.solve.failure import Failure, breakdown, by_cause
from gendex_envs.errors import FAILURE_CAUSES, ExecutionError
from gendex_envs.placement import Footprint, Item, overlap, place


def _t(*rows):
    return torch.tensor(rows, dtype=torch.float32)


def test_overlap_separates_rectangles_by_their_axes():
    fp = Footprint((0.0, 0.0), (0.10, 0.02))  # a 20 x 4 cm stick
    zero = torch.zeros(1)
    # side by side along y, 6 cm apart: free; 3 cm apart: they touch
    assert not overlap(_t((0, 0)), zero, fp, _t((0, 0.06)), zero, fp, gap=0.0)
    assert overlap(_t((0, 0)), zero, fp, _t((0, 0.03)), zero, fp, gap=0.0)
    # a gap requirement turns "just free" into "too close"
    assert overlap(_t((0, 0)), zero, fp, _t((0, 0.045)), zero, fp, gap=0.01)
    # turned by 90 degrees the second stick reaches across y: it now crosses the first
    assert overlap(_t((0, 0)), zero, fp, _t((0, 0.09)), torch.full((1,), math.pi / 2), fp, gap=0.0)
    # a diagonal placement that axis-aligned boxes would call overlapping is free (separating axis of the turned one)
    sq = Footprint((0.0, 0.0), (0.05, 0.05))
    assert not overlap(_t((0, 0)), zero, sq, _t((0.115, 0.115)), torch.full((1,), math.pi / 4), sq, gap=0.0)


def test_place_keeps_every_layout_free_of_overlaps_and_on_the_table():
    torch.manual_seed(0)
    box = Footprint((0.0, 0.0), (0.05, 0.05))
    # six 10 cm boxes 13 cm apart, each moving +-8 cm: crowded enough that draws collide and layouts are redrawn
    items = [Item(f"o{i}", (0.13 * (i % 3), 0.13 * (i // 3)), (0.08, 0.08), math.pi, box) for i in range(6)]
    noise = place(items, 200, (0.8, 0.6))
    centres = {it.name: torch.tensor(it.pos) + noise[it.name][0] for it in items}
    for i, a in enumerate(items):
        dxy, dyaw = noise[a.name]
        assert dxy.abs().max() <= 0.08 + 1e-6 and dyaw.abs().max() <= math.pi + 1e-6
        assert dxy.abs().max() > 0.05  # it does randomize
        for b in items[i + 1:]:
            hit = overlap(centres[a.name], noise[a.name][1], box, centres[b.name], noise[b.name][1], box, gap=0.0099)
            assert not hit.any(), (a.name, b.name)


def test_place_is_a_function_of_the_seed_and_fixed_objects_may_overhang():
    items = [Item("cabinet", (0.6, 0.1), (0.02, 0.02), 0.1, Footprint((0.0, 0.0), (0.24, 0.21)), fixed=True),
             Item("apple", (0.2, 0.0), (0.08, 0.08), math.pi, Footprint((0.0, 0.0), (0.04, 0.04)))]
    torch.manual_seed(3)
    a = place(items, 16, (0.8, 0.6))
    torch.manual_seed(3)
    b = place(items, 16, (0.8, 0.6))
    assert all(torch.equal(a[k][0], b[k][0]) for k in a)
    assert (a["cabinet"][0] != 0).all()  # overhanging the back edge, the fixed cabinet is still randomized
    loose = [Item("stick", (0.77, 0.0), (0.02, 0.02), 0.0, Footprint((0.0, 0.0), (0.05, 0.01)))]
    torch.manual_seed(0)
    out = place(loose, 32, (0.8, 0.6))["stick"][0]
    assert (out == 0).all(dim=1).all()  # nowhere on the table: it keeps its nominal pose


def test_failures_are_typed_and_survive_pickling():
    with pytest.raises(ValueError, match="unknown failure cause 'bad_luck'"):
        Failure("bad_luck")
    with pytest.raises(ValueError, match="causes:"):
        ExecutionError("x", cause="bad_luck")
    exc = ExecutionError("no grasp held", cause="grasp_failed", stage="reach_apple", skill="reach")
    back = pickle.loads(pickle.dumps(exc))
    assert (back.cause, back.stage, back.skill, str(back)) == ("grasp_failed", "reach_apple", "reach", "no grasp held")
    f = Failure.of_error(back)
    assert f.key == "reach_apple/reach/grasp_failed" and "grasp_failed in stage 'reach_apple'" in str(f)
    counts = {"a/grasp/slipped": 2, "b/carry/slipped": 3, "-/-/timeout": 1}
    assert by_cause(counts) == {"slipped": 5, "timeout": 1}
    assert breakdown(counts)[0] == ("b/carry/slipped", 3)
    assert set(by_cause(counts)) <= set(FAILURE_CAUSES)
