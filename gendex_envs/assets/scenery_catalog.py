"""The catalog of scene assets and styles: the record of what exists, how each is made and its licence.

``python -m gendex_envs.assets.scenery_catalog`` writes ``gendex_envs/assets/data/scenery/catalog.json`` (every
surface material, background image, structure, paint and style, with its generator and parameters) and a
``LICENSE`` beside it; a test checks the committed catalog against the code. :func:`guide` is the text
``gendex scenes`` prints.

Why no image files: the textures are drawn by numpy at first use (20-150 ms each, memoised per process) from a seed
per name. Committed PNGs of the 38 materials (512 px) and 26 walls (1024 x 512 px) would add 6.1 MB (optimised
PNG) to the repository and to the 10 MB wheel, and a cache directory at run time would need a writable home and
invalidation when a generator changes; generating in memory needs neither and cannot drift from the code.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import json
import logging
from pathlib import Path
from typing import Any

from gendex_envs.assets.backgrounds import BACKGROUND_SIZE, BACKGROUNDS, WALL_HEIGHT_M
from gendex_envs.assets.manifest import DATA_DIR
from gendex_envs.assets.structures import PAINTS, STRUCTURES
from gendex_envs.assets.surface_textures import MATERIALS, PERIOD_M, SURFACE_PX

log = logging.getLogger(__name__)

OUT = DATA_DIR / "scenery"
LICENCE = "Apache-2.0"
SOURCE = "GenDex procedural (numpy), own work"
LICENCE_TEXT = """The scene assets listed in catalog.json (surface materials, background images, structures, paints
and scene styles) are GenDex's own work: the textures are drawn at run time by the numpy code in
gendex_envs/assets/texture_noise.py, surface_textures.py and backgrounds.py, the structures are boxes defined in
gendex_envs/assets/structures.py, and the styles in gendex_envs/scene_styles.py. No third-party images, textures
or meshes are used and nothing is downloaded.

Licensed under the Apache License, Version 2.0 (SPDX: Apache-2.0), the licence of the GenDex project.
You may obtain a copy of the License at http://www.apache.org/licenses/LICENSE-2.0
"""


def _plain(value: Any) -> Any:
    if isinstance(value, float):
        return round(value, 4)
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    return value


def _generator(make) -> dict:
    """The generator function and its fixed parameters of a catalog entry."""
    if isinstance(make, functools.partial):
        return {"generator": f"{make.func.__module__}.{make.func.__name__}", "params": _plain(make.keywords)}
    return {"generator": f"{make.__module__}.{make.__name__}", "params": {}}


def catalog() -> dict:
    """The whole catalog as plain JSON-able data."""
    from gendex_envs.scene_styles import DEFAULT_STYLE, STYLES
    from gendex_envs.spec import omit_unset

    return {
        "licence": LICENCE, "source": SOURCE,
        "materials": {"size_px": SURFACE_PX, "period_m": PERIOD_M, "entries": [
            {"name": m.name, "description": m.description, "tags": list(m.tags), "roughness": m.roughness,
             "metallic": m.metallic, **_generator(m.make), "licence": LICENCE} for m in MATERIALS.values()]},
        "backgrounds": {"size_px": list(BACKGROUND_SIZE), "wall_height_m": WALL_HEIGHT_M, "entries": [
            {"name": b.name, "description": b.description, "place": b.place, **_generator(b.make),
             "licence": LICENCE} for b in BACKGROUNDS.values()]},
        "structures": [{"name": s.name, "description": s.description, "mount": s.mount, "palette": list(s.palette),
                        "parts": len(s.parts), "colliding_parts": sum(p.collision for p in s.parts),
                        "bounds_m": _plain([list(s.bounds_m[0]), list(s.bounds_m[1])]), "licence": LICENCE}
                       for s in STRUCTURES.values()],
        "paints": {name: _plain(list(rgb)) for name, rgb in PAINTS.items()},
        "styles": {"default": DEFAULT_STYLE,
                   "entries": {name: _plain(omit_unset(dataclasses.asdict(style))) for name, style in STYLES.items()}},
    }


def catalog_text() -> str:
    return json.dumps(catalog(), indent=1, sort_keys=False) + "\n"


def write(out: Path = OUT) -> Path:
    """Write catalog.json and LICENSE into ``out``; returns its path."""
    out.mkdir(parents=True, exist_ok=True)
    (out / "LICENSE").write_text(LICENCE_TEXT)
    path = out / "catalog.json"
    path.write_text(catalog_text())
    log.info("wrote %s", path)
    return path


def guide() -> str:
    """What a task's ``scene`` section can name: styles, materials, backgrounds, structures and paints."""
    from gendex_envs.scene_styles import DEFAULT_STYLE, STYLES

    lines = [f"Scene styles (scene: {{style: NAME}}; default {DEFAULT_STYLE}):"]
    for name, style in STYLES.items():
        structures = ", ".join(f"{s.name} ({s.kind})" for s in style.structures) or "none"
        lines.append(f"  {name:9s} surfaces {', '.join(style.surface.materials)}; backgrounds "
                     f"{', '.join(style.background.images)}; structures {structures}")
    lines.append(f"\nSurface materials ({len(MATERIALS)}; scene.surface.materials, scene.floor.materials):")
    lines += [f"  {m.name:16s} {m.description} [{', '.join(m.tags)}]" for m in MATERIALS.values()]
    lines.append(f"\nBackgrounds ({len(BACKGROUNDS)}; scene.background.images):")
    lines += [f"  {b.name:22s} {b.place:9s} {b.description}" for b in BACKGROUNDS.values()]
    lines.append(f"\nStructures ({len(STRUCTURES)}; scene.structures[].kind):")
    lines += [f"  {s.name:16s} {s.description}" for s in STRUCTURES.values()]
    lines.append(f"\nPaints (scene.structures[].colors): {', '.join(PAINTS)}")
    lines.append(f"\nAll own work, {LICENCE}; the record: gendex_envs/assets/data/scenery/catalog.json")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description="Write the scenery catalog.json and LICENSE.")
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    write(args.out)


if __name__ == "__main__":
    main()
