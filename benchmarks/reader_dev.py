"""How the instruction reader does on its dev set (``tests/data/instructions/dev.yaml``), or on another set.

Counts, for requests with an expected reading: read as expected, said (read with a note naming what it did not
build, e.g. a colour), refused, misread; for requests that must be refused: refused, read anyway. The default
suite's ``tests/unit/test_dev_set.py`` holds misreads at 0; this prints the progress figure (issue 45's goal: 90 %
read as expected).

Usage::

    .venv/bin/python benchmarks/reader_dev.py [--set tests/data/instructions/dev.yaml] [--show refused]
"""

from __future__ import annotations

import argparse
import collections
import json
import sys
from pathlib import Path

# isort: off
import gendex_envs.blas  # noqa: F401 - first: it pins OpenBLAS's kernels before numpy loads
# isort: on

import yaml

from generator.catalog_view import asset_dicts
from generator.instruction import InstructionError, read_instruction

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "unit"))
from test_dev_set import _misread  # noqa: E402 - the test's own judgement of a reading


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--set", type=Path, default=ROOT / "tests/data/instructions/dev.yaml")
    ap.add_argument("--show", choices=["expected", "said", "refused", "misread", "none"], default="none")
    args = ap.parse_args(argv)
    entries = yaml.safe_load(args.set.read_text())
    assets = asset_dicts()
    counts: collections.Counter = collections.Counter()
    for e in entries:
        try:
            reading = read_instruction(e["text"], assets)
        except InstructionError as exc:
            outcome, detail = "refused", str(exc).splitlines()[0]
        else:
            if "refuse" in e:
                outcome, detail = "read anyway", reading.skill
            else:
                why = _misread(reading, e["read"])
                said = why is None and any(n for n in reading.notes if "not built yet" in n)
                outcome, detail = ("misread", why) if why else (("said", "; ".join(reading.notes)) if said
                                                                 else ("expected", reading.skill))
        kind = "refuse" if "refuse" in e else "read"
        counts[kind, outcome] += 1
        if args.show == outcome:
            print(f"{e['text']!r}: {detail}")
    reads = sum(n for (k, _), n in counts.items() if k == "read")
    summary = {f"{k}: {o}": n for (k, o), n in sorted(counts.items())}
    summary["read as expected"] = f"{counts['read', 'expected']}/{reads}"
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
