"""Text and JSON views of the catalog: what ``gendex assets`` prints and what proposal prompts consume."""

from __future__ import annotations

from dataclasses import asdict

from gendex_envs.assets.catalog import AssetRecord, catalog


def _cm(size_m) -> str:
    return " x ".join(f"{100 * v:.1f}" for v in size_m)


def asset_summary(record: AssetRecord) -> dict:
    """A JSON-able summary of one asset (what ``gendex assets --json`` lists)."""
    e = record.entry
    out = {
        "id": e.id, "category": e.category, "kind": e.kind, "tags": list(e.tags), "size_m": list(e.size_m),
        "mass_kg": e.mass_kg, "friction": e.friction, "source": e.source, "licence": e.licence,
    }
    if record.articulated:
        out["fixed_base"] = e.fixed_base
        out["joints"] = [asdict(j) for j in e.joints]
        if "color" in e.params:  # the colour people call it by ('the red button')
            out["color"] = e.params["color"]
    return out


def catalog_json() -> dict:
    """Machine-readable catalog: ``{"assets": [...], "counts": {...}}``."""
    records = sorted(catalog().values(), key=lambda r: r.id)
    rigid = [r for r in records if not r.articulated]
    arts = [r for r in records if r.articulated]
    categories: dict[str, int] = {}
    for r in arts:
        categories[r.category] = categories.get(r.category, 0) + 1
    return {
        "assets": [asset_summary(r) for r in records],
        "counts": {"rigid": len(rigid), "articulated": len(arts), "articulated_categories": categories},
    }


def guidance_text(not_graspable: dict[str, str] | None = None) -> str:
    """The block of text the proposal prompts get: the rigid objects grouped by category (the tags its objects share,
    then each id with its real size and mass, and what sets it apart), then every articulated asset with its
    joints. ``not_graspable``: ids the hand does not reliably hold, with why (marked, so a prompt does not ask it
    to grasp them)."""
    not_graspable = not_graspable or {}
    records = sorted(catalog().values(), key=lambda r: (r.articulated, r.category, r.id))
    rigid = [r for r in records if not r.articulated]
    lines = ["Objects by category (the tags its objects share: each id, size cm x*y*z at scale 1, mass kg):"]
    for category in dict.fromkeys(r.category for r in rigid):
        group = [r for r in rigid if r.category == category]
        shared = [t for t in group[0].tags if all(t in r.tags for r in group)]
        items = []
        for r in group:
            extra = [t for t in r.tags if t not in shared]
            why = not_graspable.get(r.id)
            notes = extra + ([f"not graspable: {why}"] if why else [])
            items.append(f"{r.id} {_cm(r.size_m)}, {r.mass_kg:.3g}"
                         + (f" ({'; '.join(notes)})" if notes else ""))
        lines.append(f"- {category} ({', '.join(shared)}): " + "; ".join(items))
    lines += ["", "Articulated objects (id | category | size cm | base | joints: name type [limits] closed->open, "
                  "handle link):"]
    for r in (r for r in records if r.articulated):
        joints = "; ".join(f"{j.name} {j.type} [{j.limits[0]:.3g}, {j.limits[1]:.3g}] {j.closed_qpos:.3g}->"
                           f"{j.open_qpos:.3g}, handle {j.handle_link}" for j in r.joints)
        base = "fixed" if r.entry.fixed_base else "free"
        lines.append(f"- {r.id} | {r.category} | {_cm(r.size_m)} | {base} | {joints}")
    lines += ["", "Sizes are real-world at scale 1; a scale in [0.3, 2.0] multiplies every dimension. The table top is "
                  "z = 0; the robot base stands at (-0.8, 0, 0) facing +x; fronts of articulated objects face -x."]
    return "\n".join(lines)
