"""The procedural scene assets: enough of each kind, deterministic, distinct, tileable where they repeat, with
something to see where the cameras look; structures are sound boxes painted from known paints."""

import hashlib
import json

import numpy as np
import pytest

from gendex_envs.assets.backgrounds import BACKGROUND_SIZE, BACKGROUNDS, WALL_HEIGHT_M, background_image
from gendex_envs.assets.structures import PAINTS, ROLE_COLORS, ROLES, STRUCTURES
from gendex_envs.assets.surface_textures import MATERIALS, SURFACE_PX, material_image


def test_the_catalogs_hold_what_the_issue_asks_for():
    assert len(MATERIALS) >= 20 and len(BACKGROUNDS) >= 20 and len(STRUCTURES) >= 10
    kinds = {t for m in MATERIALS.values() for t in m.tags}
    assert {"wood", "stone", "laminate", "metal", "cloth", "tile"} <= kinds
    assert {b.place for b in BACKGROUNDS.values()} >= {"kitchen", "lab", "office", "workshop", "dining"}


@pytest.mark.parametrize("make, names, shape", [(material_image, sorted(MATERIALS), (SURFACE_PX, SURFACE_PX, 4)),
                                                (background_image, sorted(BACKGROUNDS), (*BACKGROUND_SIZE, 4))])
def test_images_are_deterministic_and_distinct(make, names, shape):
    digests = {}
    for name in names:
        img = make(name)
        assert img.shape == shape and img.dtype == np.uint8 and not img.flags.writeable
        assert (img[..., 3] == 255).all()
        digests[name] = hashlib.sha256(img.tobytes()).hexdigest()
    make.cache_clear()  # drawn again from scratch: the same bytes
    assert {n: hashlib.sha256(make(n).tobytes()).hexdigest() for n in names} == digests
    assert len(set(digests.values())) == len(names), "two names draw the same image"


def test_surface_materials_tile_without_a_seam():
    """A material repeats across a table or floor: the jump from its last column (row) to its first is no larger
    than the sharpest edge inside it (a plain gradient's seam would be many times larger)."""
    for name in MATERIALS:
        img = material_image(name)[..., :3].astype(float)
        for axis in (0, 1):
            inner = np.abs(np.diff(img, axis=axis)).mean(axis=(1 - axis, 2))  # [n - 1] one per line pair
            seam = np.abs(np.take(img, 0, axis=axis) - np.take(img, -1, axis=axis)).mean()
            assert seam <= inner.max() + 1.0, f"{name}: seam {seam:.1f} along axis {axis} > {inner.max():.1f}"


def test_gradients_would_fail_the_seam_check():
    ramp = np.linspace(0, 255, SURFACE_PX)[None, :, None] * np.ones((SURFACE_PX, 1, 3))
    inner = np.abs(np.diff(ramp, axis=1)).mean(axis=(0, 2))
    assert np.abs(ramp[:, 0] - ramp[:, -1]).mean() > 10 * (inner.max() + 1.0)


def test_backgrounds_show_something_where_the_side_views_look():
    """The side views see a wall from the floor to about 1.2 m (the image's lower half): every image varies
    there, and is not black."""
    rows = int(BACKGROUND_SIZE[0] * (1 - 1.2 / WALL_HEIGHT_M))
    for name in BACKGROUNDS:
        lower = background_image(name)[rows:, :, :3].astype(float)
        assert lower.std() > 5.0 and lower.mean() > 60, f"{name}: lower half std {lower.std():.1f}"


def test_structures_are_sound_and_painted_from_known_paints():
    for name, s in STRUCTURES.items():
        assert s.name == name and s.description
        assert any(p.collision for p in s.parts), f"{name} has nothing to collide with"
        assert all(min(p.size_m) > 0 for p in s.parts)
        assert all(p.role in ROLES for p in s.parts) and set(ROLES) == {"body", *ROLE_COLORS}
        assert s.palette and set(s.palette) <= set(PAINTS)
        lo, hi = s.bounds_m
        if s.mount == "stands":
            assert lo[2] == pytest.approx(0.0, abs=1e-9), f"{name} does not stand on its base"
        assert all(h - lo_ > 0.01 for lo_, h in zip(lo, hi, strict=True))
    glass = [p for s in STRUCTURES.values() for p in s.parts if p.role == "glass"]
    assert glass and not any(p.collision for p in glass)  # panes are seen, never touched



def test_the_committed_catalog_is_the_codes():
    """gendex_envs/assets/data/scenery/catalog.json records every asset with its generator, parameters and licence;
    regenerate it with ``python -m gendex_envs.assets.scenery_catalog`` after changing an asset."""
    from gendex_envs.assets.scenery_catalog import OUT, catalog_text

    assert (OUT / "catalog.json").read_text() == catalog_text()
    assert "Apache" in (OUT / "LICENSE").read_text()
    record = json.loads(catalog_text())
    assert [m["name"] for m in record["materials"]["entries"]] == list(MATERIALS)
    assert [b["name"] for b in record["backgrounds"]["entries"]] == list(BACKGROUNDS)
    assert [s["name"] for s in record["structures"]] == list(STRUCTURES)
    assert all(e["licence"] == "Apache-2.0" for e in record["materials"]["entries"] + record["backgrounds"]["entries"]
               + record["structures"])
