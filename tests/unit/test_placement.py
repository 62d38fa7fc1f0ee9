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


def test_an_object_that_starts_in_a_container_moves_with_it_and_is_never_kept_apart_from_it():
    """*Take the apple out of the bowl*: the apple's nominal place is in the bowl; drawn apart like two objects on
    the table, every layout would fail and fall back to the nominal one (no randomization at all)."""
    torch.manual_seed(0)
    bowl, apple = Footprint((0.0, 0.0), (0.075, 0.075)), Footprint((0.0, 0.0), (0.04, 0.04))
    block = Footprint((0.0, 0.0), (0.03, 0.03))
    items = [Item("apple", (0.1, 0.1), (0.0, 0.0), math.pi, apple, starts_in="bowl"),  # before its container
             Item("bowl", (0.1, 0.1), (0.08, 0.08), math.pi, bowl),
             Item("block", (0.1, -0.15), (0.08, 0.08), 0.0, block)]
    noise = place(items, 300, (0.8, 0.6))
    assert torch.equal(noise["apple"][0], noise["bowl"][0])  # the container's xy noise
    assert noise["bowl"][0].abs().max() > 0.05 and noise["apple"][1].abs().max() > 1.0  # randomized, own yaw
    bowl_at = torch.tensor((0.1, 0.1)) + noise["bowl"][0]
    block_at = torch.tensor((0.1, -0.15)) + noise["block"][0]
    assert not overlap(bowl_at, noise["bowl"][1], bowl, block_at, noise["block"][1], block).any()


def test_starts_in_is_a_rigid_container_under_a_raised_object():
    from types import SimpleNamespace as NS

    from gendex_envs.placement import starts_in

    rec = {"apple": NS(articulated=False, tags=("fruit",), size_m=(0.08, 0.08, 0.08)),
           "bowl": NS(articulated=False, tags=("container",), size_m=(0.15, 0.15, 0.06)),
           "plate": NS(articulated=False, tags=("plate",), size_m=(0.2, 0.2, 0.02))}
    apple = NS(name="apple", pos_m=(0.12, 0.1, 0.01), scale=1.0)
    bowl = NS(name="bowl", pos_m=(0.1, 0.1, 0.0), scale=1.0)
    plate = NS(name="plate", pos_m=(0.1, 0.1, 0.0), scale=1.0)
    assert starts_in(apple, [apple, bowl], rec) == "bowl"
    assert starts_in(NS(name="apple", pos_m=(0.12, 0.1, 0.0), scale=1.0), [bowl], rec) is None  # on the table
    assert starts_in(NS(name="apple", pos_m=(0.2, 0.1, 0.01), scale=1.0), [bowl], rec) is None  # beside it
    assert starts_in(apple, [apple, plate], rec) is None  # a plate holds nothing in it
