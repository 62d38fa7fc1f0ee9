"""What is poured and what pours it: beads are small loose pieces (not for grasping), the pouring vessels are tall
enough for a side grasp, the beads laid in a vessel clear its walls and each other, and the ``poured`` condition is
about the pieces that start in its vessel."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import yaml
from hulls import inside_hulls

from gendex_envs.assets.catalog import get_asset
from gendex_envs.assets.procedural_shapes import GENERATORS
from gendex_envs.errors import TaskSpecError
from gendex_envs.pouring import fill_layout, spec_pieces
from gendex_envs.spec import parse_task_spec

POURERS = ("tumbler", "beaker", "paper_cup")


def test_beads_are_loose_pieces_and_the_pourers_tall_open_vessels():
    for bead in ("bead", "marble"):
        rec = get_asset(bead)
        assert "pourable" in rec.tags and "graspable" not in rec.tags
        assert 0.012 <= rec.bbox_max_m[2] <= 0.025  # smaller than a fingertip, larger than sand
    for vessel in POURERS:
        rec = get_asset(vessel)
        assert {"pourer", "container", "graspable"} <= set(rec.tags)
        assert rec.bbox_max_m[2] >= 0.13  # the side grasp holds a vessel at 10 cm, under its rim
        assert 2 * rec.bbox_max_m[0] <= 0.075  # and closes round one at most 7.5 cm wide


@pytest.mark.parametrize("vessel", POURERS)
def test_beads_laid_in_a_vessel_clear_its_walls_and_each_other(vessel):
    bead = get_asset("bead")
    r = bead.bbox_max_m[2] / 2
    laid = fill_layout(get_asset(vessel), bead, 12)
    centres = np.array([[dx, dy, z + r] for dx, dy, z in laid])
    for a, b in itertools.combinations(centres, 2):
        assert np.linalg.norm(a - b) >= 2 * r
    sphere = np.array([[np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v)]
                       for u in np.linspace(0, 2 * np.pi, 16) for v in np.linspace(0, np.pi, 9)])
    shape = GENERATORS[vessel]()
    for c in centres:
        assert not inside_hulls(shape.hulls, c + (r - 0.0005) * sphere).any()  # none laid into the glass
    assert centres[:, 2].min() - r >= get_asset(vessel).entry.params["cavity_z"]  # on its floor, not under it
    with pytest.raises(ValueError, match="do not fit"):
        fill_layout(get_asset(vessel), bead, 200)


def _spec(extra_bead_at=None) -> dict:
    beads = [{"name": f"bead_{k}", "asset": "bead", "pos_m": [dx, 0.1 + dy, z]}
             for k, (dx, dy, z) in enumerate(fill_layout(get_asset("tumbler"), get_asset("bead"), 4))]
    if extra_bead_at is not None:
        beads.append({"name": "loose", "asset": "bead", "pos_m": list(extra_bead_at)})
    return yaml.safe_load(yaml.safe_dump({
        "name": "PourSpec", "instruction": "Pour the beads into the bowl.",
        "objects": [{"name": "glass", "asset": "tumbler", "pos_m": [0.0, 0.1, 0.0]},
                    {"name": "bowl", "asset": "bowl", "pos_m": [0.1, -0.15, 0.0]}, *beads],
        "stages": [{"name": "pour_bowl", "instruction": "Pour.", "skill": "pour", "method": "RL",
                    "control_joint": "arm", "horizon": 200, "target": "bowl"}],
        "success": {"description": "Poured.", "conditions": [
            {"type": "poured", "object": "glass", "target": "bowl", "min_fraction": 0.75}]}}))


def test_the_pieces_are_the_beads_that_start_in_the_vessel():
    spec = parse_task_spec(_spec(extra_bead_at=(-0.2, 0.0, 0.0)))  # a fifth bead on the table
    records = {o.name: get_asset(o.asset) for o in spec.objects}
    assert spec_pieces(spec, records, "glass") == ("bead_0", "bead_1", "bead_2", "bead_3")
    assert spec_pieces(spec, records, "bowl") == ()


def test_a_poured_condition_needs_its_share_and_its_container():
    raw = _spec()
    del raw["success"]["conditions"][0]["min_fraction"]
    with pytest.raises(TaskSpecError, match="min_fraction is required for type 'poured'"):
        parse_task_spec(raw)
    raw = _spec()
    raw["success"]["conditions"][0]["min_fraction"] = 1.5
    with pytest.raises(TaskSpecError, match="min_fraction = 1.5 is not allowed"):
        parse_task_spec(raw)
