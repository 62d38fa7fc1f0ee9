"""The things a mug hangs on, and the mug's handle: each stand's pegs rise towards their tips from the post, with
room round them, and the mug's recorded handle opening is open, wide enough round an 8 mm peg."""

from __future__ import annotations

import numpy as np
import pytest
from hulls import inside_hulls

from gendex_envs.assets.catalog import get_asset
from gendex_envs.assets.procedural_hanging import PEG_RADIUS_CM, PEG_RISE_DEG
from gendex_envs.assets.procedural_shapes import GENERATORS


@pytest.mark.parametrize("stand, pegs", [("mug_hook", 1), ("mug_tree", 3), ("mug_rack", 2)])
def test_every_peg_rises_towards_its_tip_from_the_stand(stand, pegs):
    shape = GENERATORS[stand]()
    e = get_asset(stand).entry
    assert "hang_on" in e.tags and e.params["pegs"] == pegs
    for k in range(pegs):
        root, tip = (np.array([e.params[f"peg{k}_{end}_{a}"] for a in "xyz"]) for end in ("root", "tip"))
        d = tip - root
        assert 0.07 <= np.linalg.norm(d) <= 0.1
        assert np.degrees(np.arcsin(d[2] / np.linalg.norm(d))) == pytest.approx(PEG_RISE_DEG, abs=0.1)
        axis = root + np.linspace(0.0, 1.0, 9)[:, None] * d
        assert inside_hulls(shape.hulls, axis[1:]).all()  # the peg is solid along its axis
        above = axis + [0.0, 0.0, PEG_RADIUS_CM / 100 + 0.01]
        # and free a centimetre over it, where a handle's top rests
        assert not inside_hulls(shape.hulls, above[2:]).any()


def test_the_mug_handle_opening_is_open_round_a_peg():
    shape = GENERATORS["mug"]()
    e = get_asset("mug").entry
    assert "hangable" in e.tags
    hole = np.array([e.params[f"handle_hole_{a}"] for a in "xyz"])
    r = PEG_RADIUS_CM / 100 + 0.004  # a peg with 4 mm to spare each way
    ring = hole + np.array([[r * np.cos(a), y, r * np.sin(a)] for a in np.linspace(0, 2 * np.pi, 24, endpoint=False)
                            for y in (-0.008, 0.0, 0.008)])
    assert not inside_hulls(shape.hulls, ring).any()
    # the handle above and below the opening
    assert inside_hulls(shape.hulls, hole + np.array([[0.0, 0.0, 0.025], [0.0, 0.0, -0.025]])).all()
