"""The catalog as users and prompts see it: `gendex assets --json` / `--guidance`, and lookup errors."""

import json
import re

import pytest
from typer.testing import CliRunner

from gendex.cli import app
from gendex.solve.lift_check import measured_rates
from gendex_envs.assets.catalog import catalog, get_asset
from gendex_envs.assets.guidance import guidance_text
from gendex_envs.errors import AssetNotFoundError
from generator.backends.roles import MIN_GRASP_RATE


@pytest.fixture(scope="module")
def listing():
    result = CliRunner().invoke(app, ["assets", "--json"])
    assert result.exit_code == 0, result.output
    return json.loads(result.output)


def test_json_listing_meets_the_library_targets(listing):
    rigid = [a for a in listing["assets"] if a["kind"] == "rigid"]
    articulated = [a for a in listing["assets"] if a["kind"] == "articulated"]
    assert len(rigid) >= 40
    categories: dict[str, int] = {}
    for a in articulated:
        categories[a["category"]] = categories.get(a["category"], 0) + 1
    assert len(categories) >= 10 and min(categories.values()) >= 2, categories
    assert listing["counts"]["articulated_categories"] == categories
    for a in listing["assets"]:
        assert len(a["size_m"]) == 3 and all(0.002 < v < 1.5 for v in a["size_m"]), a["id"]  # a spill: 3 mm
        assert 0.001 < a["mass_kg"] < 60, a["id"]
        assert a["licence"], a["id"]
    for a in articulated:
        assert a["joints"] and all(j["handle_link"] for j in a["joints"]), a["id"]


def test_yaml_vocabulary_is_covered(listing):
    categories = {a["category"] for a in listing["assets"]}
    for noun in ("apple", "banana", "orange", "lemon", "pear", "peach", "plum", "tennis_ball", "baseball",
                 "golf_ball", "softball", "mug", "cup", "bowl", "plate", "pitcher", "bottle", "can", "jar",
                 "cracker_box", "sugar_box", "pudding_box", "hammer", "screwdriver", "spatula", "marker", "scissors",
                 "spoon", "fork", "knife", "sponge"):
        assert noun in categories, noun


def test_guidance_names_every_asset_with_size():
    result = CliRunner().invoke(app, ["assets", "--guidance"])
    assert result.exit_code == 0
    text = result.output
    for asset_id in ("cabinet_left_hinge", "drawer_chest_2"):
        assert f"- {asset_id} |" in text
    assert "door_hinge revolute [0, 1.9] 0->1.4, handle door" in text
    # rigid objects one line per category: the tags they share, then each id with size and mass
    assert "- bowl (graspable, container, tableware, kitchenware): bowl 15.0 x 15.0 x 6.3, 0.25; bowl_blue 15.0" in text
    assert "- apple (graspable, food, fruit): apple 7.5 x 7.7 x 7.0, 0.15; apple_green 7.5 x 7.7 x 7.0, 0.15;" in text
    assert "; apple_scan 8.0 x 7.8 x 8.8, 0.16 (textured)" in text  # a tag not all apples have
    for r in catalog().values():
        assert f" {r.id} " in text or f"- {r.id} |" in text, r.id


def test_guidance_marks_objects_the_hand_does_not_hold():
    from generator.catalog_view import guidance

    text = guidance_text({"apple": "held in 50 % of recorded lifts"})
    assert "apple 7.5 x 7.7 x 7.0, 0.15 (not graspable: held in 50 % of recorded lifts)" in text
    assert "(not graspable" not in guidance_text()
    text, rates = guidance(), measured_rates()
    for asset_id, rate in rates.items():  # each measured object is marked exactly when it is held too rarely
        marked = re.search(rf"[:;] {asset_id} [^;\n]*\(not graspable: held in \d+% of recorded lifts\)", text)
        assert bool(marked) == (rate < MIN_GRASP_RATE), asset_id


def test_unknown_asset_suggests_close_ids():
    with pytest.raises(AssetNotFoundError, match=r"unknown asset 'appel'.*'apple'"):
        get_asset("appel")


def test_shipped_meshes_rebuild_identically(tmp_path):
    """The converted package meshes are reproducible from the installed packages."""
    import filecmp

    from gendex_envs.assets.build_shipped import DEFAULT_OUT, build

    build(tmp_path)
    for path in sorted(p for p in tmp_path.rglob("*") if p.is_file()):
        assert filecmp.cmp(path, DEFAULT_OUT / path.relative_to(tmp_path), shallow=False), path.name
    record = get_asset("apple_scan")
    assert record.entry.visual.endswith(".glb") and 0.07 < record.size_m[0] < 0.09


def test_held_summary_says_how_the_solver_holds_each_graspable_object(tmp_path):
    from gendex.solve.lift_check import held_summary, write_record

    write_record([{"asset": "apple", "held": 20, "attempts": 20, "scale": 1.0},
                  {"asset": "fork", "held": 3, "attempts": 20, "scale": 1.0}], [1], tmp_path / "rec.json")
    held = held_summary(0.9, tmp_path / "rec.json")
    assert held["apple"] == "20/20" and held["fork"] == "**not graspable** (3/20)"
    assert held["banana"] == "not measured"
    assert "basket" not in held and "cabinet_left_hinge" not in held  # nothing to grasp
    assert set(held) == {k for k, r in catalog().items() if "graspable" in r.tags and not r.articulated}


def test_the_asset_gallery_shows_every_asset():
    """docs/assets.md (`gendex gallery`) has a row and a picture for every catalog asset, and says how each
    graspable object is held as the committed record does."""
    from pathlib import Path

    from gendex.solve.lift_check import held_summary

    docs = Path(__file__).parents[2] / "docs"
    text = (docs / "assets.md").read_text()
    held = held_summary(MIN_GRASP_RATE)
    for asset_id, record in catalog().items():
        if record.root == Path("/"):  # a user-supplied dataset's (YCB, PartNet-Mobility): not shipped
            continue
        row = next((line for line in text.splitlines() if f"| `{asset_id}` |" in line), None)
        assert row is not None, asset_id
        assert (docs / "assets" / f"{asset_id}.png").is_file(), asset_id
        if asset_id in held:
            assert f"| {held[asset_id]} |" in row, (asset_id, row)
