"""The catalog object nearest in meaning to an object a request names that the catalog lacks (*grab the grapefruit*:
a fruit, the pear, not the paper cup its letters are nearest to).

The reader narrows the objects to those that can play the part, and to the kind a word of the phrase says where one
does (*dragon fruit*: a fruit); :func:`nearest` then takes the category whose name is nearest to the phrase by
all-MiniLM-L6-v2 sentence embeddings (the model of the ``stats`` extra; :mod:`generator.embedding`, each text
embedded once and cached), and within it the model whose id is nearest. A phrase no category is near
(:data:`MIN_SIMILARITY`) is not substituted: the request is refused, naming the nearest objects and how near they
were, so nothing is built that the person did not ask for; where one category alone can play the part (the beads
and marbles poured), it stands in, with its cosine said."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import TYPE_CHECKING

from generator.errors import InstructionError
from generator.vocabulary import KINDS

if TYPE_CHECKING:
    from generator.instruction import Mention

MIN_SIMILARITY = 0.45
"""Cosine a category's name needs with the phrase to stand in for it. Measured on names the catalog lacks, against
every graspable category:
football -> baseball 0.67, soda bottle -> bottle 0.76, cereal box -> pudding box 0.69, grapefruit -> strawberry 0.57,
teacup -> cup 0.66; below: hairbrush -> bottle 0.36, ladle -> golf ball 0.41, cookie -> sugar box 0.41."""


def _spoken(name: str) -> str:
    return name.replace("_", " ")


def nearest(phrase: str, able: Sequence[dict], role: str) -> tuple[dict, float]:
    """The asset of ``able`` nearest in meaning to ``phrase`` and its category's cosine with it;
    :class:`InstructionError` when none is near enough (:data:`MIN_SIMILARITY`) or the sentence encoder is not
    installed. ``role``: the part the object plays (for the message)."""
    from generator.embedding import embed_each

    categories = sorted({a["category"] for a in able})
    try:
        vectors, _ = embed_each([phrase, *(_spoken(c) for c in categories)])
    except ImportError as exc:
        raise InstructionError(
            f"'{phrase}' is not in the catalog, and finding the nearest object by meaning needs the sentence "
            f"encoder of the 'stats' extra (pip install 'gendex[stats]'; missing: {exc.name}). Name a catalog "
            f"object instead: {', '.join(categories)}") from None
    sims = vectors[1:] @ vectors[0]
    order = sorted(range(len(categories)), key=lambda k: (-float(sims[k]), categories[k]))
    best = order[0]
    if float(sims[best]) < MIN_SIMILARITY and len(categories) > 1:  # one kind plays the part: no choice to make
        # ('pour the rice': the catalog's only pourable things are beads and marbles)
        near = ", ".join(f"{_spoken(categories[k])} {float(sims[k]):.2f}" for k in order[:3])
        raise InstructionError(
            f"'{phrase}' is not in the catalog, and no {role} object is near it in meaning (nearest: {near}; a "
            f"stand-in needs {MIN_SIMILARITY:.2f}). Name one of: {', '.join(_spoken(c) for c in categories)}")
    models = sorted((a for a in able if a["category"] == categories[best]), key=lambda a: a["id"])
    if len(models) > 1:
        ids, _ = embed_each([_spoken(a["id"]) for a in models])
        models = [models[int((ids @ vectors[0]).argmax())]]
    return models[0], float(sims[best])


def stand_in(m: Mention, able: Sequence[dict], role: str, skill: str, into: dict | None = None) -> Mention:
    """``m`` (an object the catalog lacks) resolved to its stand-in among the ``able`` objects of its ``role``: of the
    kind a word of it says where one does (*toy car*: a toy), one the solver holds for a grasp, one that fits in
    ``into`` (the container of a put-in) where one does, then :func:`nearest` in meaning."""
    from generator.backends.roles import fits_in, graspable

    kind = next((KINDS[w] for w in reversed(m.phrase.split()) if w in KINDS), None)
    pool = [a for a in able if kind in a["tags"]] or list(able)
    if role == "graspable":  # a stand-in the solver holds, so the author builds the object said here
        pool = [a for a in pool if graspable(a)] or pool
        if into is not None:  # 'put the pineapple in the bowl': a fruit that goes in it
            pool = [a for a in pool if fits_in(a, into)] or pool
    if not pool:
        raise InstructionError(f"nothing in the catalog can be the {role} object of '{skill}'")
    best, cosine = nearest(m.phrase, pool, role)
    among = f" among the {kind} objects" if kind and kind in best["tags"] else ""
    return dataclasses.replace(m, asset=best["id"], options=(best["id"],),
                               detail=f"not in the catalog; the {role} object nearest in meaning{among}, "
                                      f"cosine {cosine:.2f}")


__all__ = ["MIN_SIMILARITY", "nearest", "stand_in"]
