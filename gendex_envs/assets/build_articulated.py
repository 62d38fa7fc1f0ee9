"""Write the procedural articulated library: ``<out>/<id>/model.urdf`` per variant plus ``<out>/manifest.json``.

    python -m gendex_envs.assets.build_articulated [--out DIR]

Deterministic: rerunning gives byte-identical files (no timestamps, fixed float formatting, sorted ids).
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from gendex_envs.assets.articulated import all_models
from gendex_envs.assets.manifest import DATA_DIR, MANIFEST, write_manifest

log = logging.getLogger(__name__)

DEFAULT_OUT = DATA_DIR / "articulated"
NOTE = ("Procedural articulated assets (gendex_envs/assets/articulated.py): URDF primitives only, front faces -x, "
        "bbox at the closed pose, mass_kg = total of all links. Regenerate with "
        "python -m gendex_envs.assets.build_articulated")


def build(out: Path = DEFAULT_OUT) -> list[Path]:
    """Write every variant's URDF and the manifest under ``out``; returns the written paths."""
    out = Path(out)
    written, entries = [], []
    for model in all_models():
        rel = f"{model.id}/model.urdf"
        path = out / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(model.urdf())
        written.append(path)
        entries.append(model.entry(rel))
    write_manifest(out / MANIFEST, entries, note=NOTE)
    written.append(out / MANIFEST)
    log.info("wrote %d articulated assets to %s", len(entries), out)
    return written


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help=f"output folder (default {DEFAULT_OUT})")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    build(args.out)


if __name__ == "__main__":
    main()
