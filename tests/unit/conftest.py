"""Fixtures shared by the unit tests."""

from __future__ import annotations

import dataclasses

import pytest

from generator.backends.base import ModelRequest
from generator.backends.offline import OfflineBackend
from generator.catalog_view import asset_dicts
from generator.instruction import read_instruction
from generator.steps.propose import parse_proposal
from generator.steps.scene import adjust_sizes, parse_scene


@pytest.fixture
def guided():
    """``guided(text, seed=5)``: the offline author's proposal for request ``text`` and the task spec its scene
    answer makes (sizes fitted), as the pipeline's propose and scene steps would have them."""

    def write(text: str, seed: int = 5):
        b = OfflineBackend(seed=seed)
        reading = read_instruction(text, asset_dicts())
        answer = b.complete(ModelRequest(step="propose_guided", prompt="", context={
            "reading": reading.to_dict(), "assets": asset_dicts()})).text
        p = parse_proposal(answer)
        ids = {o.asset for o in p.objects}
        context = {"proposal": dataclasses.asdict(p), "assets": [a for a in asset_dicts() if a["id"] in ids],
                   "candidate_index": 0, "index": 0, "attempt": 0}
        scene = b.complete(ModelRequest(step="scene", prompt="", context=context)).text
        return p, adjust_sizes(parse_scene(scene, p), p)

    return write
