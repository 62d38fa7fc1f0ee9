"""How far the offline author's grammar can still move the library's commands-only diversity: every task it can
still write (not an existing name, nor the skills and object kinds of an existing task), each drawn command's mean
all-MiniLM-L6-v2 cosine to the library's commands, and the library's mean pairwise cosine with the N least alike of
them added. Prints the kinds left, the least alike commands and one line per N.

Usage::

    .venv/bin/python benchmarks/grammar_headroom.py [--add 10 20 40]
"""

from __future__ import annotations

import argparse
from collections import Counter
from pathlib import Path

# isort: off
import gendex_envs.blas  # noqa: F401 - first: it pins OpenBLAS's kernels before numpy loads
# isort: on

import numpy as np

from generator.backends.offline import OfflineBackend
from generator.catalog_view import asset_dicts
from generator.embedding import embed, embed_each
from generator.novelty import existing_tasks, proposal_signature
from generator.phrasing import split


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--add", type=int, nargs="+", default=[10, 20, 40, 60], help="How many of the least alike to add.")
    ap.add_argument("--root", type=Path, default=Path("generated_tasks"), help="The task library.")
    args = ap.parse_args(argv)
    library = existing_tasks([args.root])
    names = {t.env_id.split("/")[1].rsplit("-v", 1)[0] for t in library}
    taken = {tuple(map(tuple, t.signature)) for t in library}
    lib = np.asarray(embed_each([split(t.instruction)[1] for t in library])[0])
    options = [(k, p) for k, p in OfflineBackend(0).task_options(list(asset_dicts()))
               if p["name"] not in names and proposal_signature(p) not in taken]
    print(f"{len(library)} library tasks; {len(options)} tasks left to write: "
          + ", ".join(f"{k} {n}" for k, n in Counter(k for k, _ in options).most_common()))
    if not options:
        return 0
    commands = [split(p["description"])[1] for _, p in options]
    emb = np.asarray(embed(commands)[0])
    cross = emb @ lib.T
    mean = cross.mean(axis=1)
    order = np.argsort(mean)
    for i in order[:10]:
        print(f"  {mean[i]:.3f} {options[i][0]:10s} {commands[i]}")
    print(f"  median {np.median(mean):.3f}")
    same = lib @ lib.T
    n = len(lib)
    print(f"commands alone now: {(same.sum() - n) / (n * (n - 1)):.3f}")
    for k in args.add:
        pick = emb[order[:k]]
        total = same.sum() - n + 2 * cross[order[:k]].sum() + (pick @ pick.T).sum() - len(pick)
        m = n + len(pick)
        print(f"with the {len(pick)} least alike added: {total / (m * (m - 1)):.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
