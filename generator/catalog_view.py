"""The catalog as the generator's prompts and the offline author see it."""

from __future__ import annotations

import functools

from gendex_envs.assets.catalog import catalog
from gendex_envs.assets.guidance import asset_summary, guidance_text


@functools.lru_cache(maxsize=1)
def asset_dicts() -> tuple[dict, ...]:
    """JSON-able summaries of every catalog asset, sorted by id (joints included for articulated ones)."""
    out = []
    for r in sorted(catalog().values(), key=lambda r: r.id):
        d = asset_summary(r)
        d["size_m"] = [round(float(v), 4) for v in d["size_m"]]
        d.setdefault("fixed_base", False)
        d.setdefault("joints", [])
        out.append(d)
    return tuple(out)


def asset_dict(asset_id: str) -> dict:
    for d in asset_dicts():
        if d["id"] == asset_id:
            return d
    raise KeyError(asset_id)


def guidance() -> str:
    """The catalog block of the proposal prompts, the graspable-tagged objects the solver does not reliably hold
    (below :data:`~generator.backends.roles.MIN_GRASP_RATE` in ``benchmarks/grasp.py``'s record) marked as such."""
    from gendex.solve.lift_check import measured_rates
    from generator.backends.roles import MIN_GRASP_RATE

    rates = measured_rates()
    weak = {a["id"]: f"held in {rates[a['id']]:.0%} of recorded lifts" for a in asset_dicts()
            if "graspable" in a["tags"] and rates.get(a["id"], 1.0) < MIN_GRASP_RATE}
    return guidance_text(weak)
