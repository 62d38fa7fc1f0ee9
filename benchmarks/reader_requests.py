"""What the offline author makes of a set of requests: each read (:func:`generator.instruction.read_instruction`)
and proposed (:func:`generator.steps.propose.propose`, the offline backend), no scene, no gate. Prints a Markdown
table (request, reading, the proposed task or the refusal's first line) for a person to judge *as asked*, *stated
substitute*, *honest refusal* or *misread*; build the ones to check through the gate with ``gendex generate
--instruction``.

Usage::

    .venv/bin/python benchmarks/reader_requests.py benchmarks/requests/s42.yaml [--seed 4200]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

# isort: off
import gendex_envs.blas  # noqa: F401 - first: it pins OpenBLAS's kernels before numpy loads
# isort: on

import yaml

from generator.catalog_view import asset_dicts
from generator.errors import GeneratorError
from generator.instruction import read_instruction


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("requests", type=Path, help="A YAML list of request strings.")
    ap.add_argument("--seed", type=int, default=4200, help="The offline author's seed of the first request (+1 each).")
    args = ap.parse_args(argv)
    from generator.backends.registry import make_backend  # after the reader: the backends import what it imports
    from generator.steps.propose import propose

    requests = yaml.safe_load(args.requests.read_text())
    assets = asset_dicts()
    print("| # | request | reading | outcome |")
    print("|---|---|---|---|")
    refused = 0
    for i, text in enumerate(requests):
        try:
            reading = read_instruction(text, assets)
            proposal, _ = propose(make_backend("offline", seed=args.seed + i), instruction=text, reading=reading)
        except GeneratorError as exc:  # a refusal (InstructionError) or an author that cannot write it
            refused += 1
            print(f"| {i + 1} | {_cell(text)} | - | refused: {_cell(str(exc).splitlines()[0])} |")
            continue
        lines = reading.lines()
        subs = "; ".join(f"{p} -> {a}" for p, a in proposal.substitutions.items())
        print(f"| {i + 1} | {_cell(text)} | {_cell(' '.join(x.strip() for x in lines[1:]))} | "
              f"{proposal.name}: {_cell(proposal.description)}" + (f" (substituted: {_cell(subs)})" if subs else "")
              + " |")
    print(f"\n{len(requests) - refused} of {len(requests)} proposed, {refused} refused")
    return 0


if __name__ == "__main__":
    sys.exit(main())
