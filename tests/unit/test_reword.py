"""Wording the library (generator.reword, generator.phrasing's framings): the command is kept, only the situation
and purpose around it are chosen, so the library reads as varied as its tasks; each change is a new version."""

from __future__ import annotations

import re

import numpy as np
import pytest
import yaml

from gendex_envs import task_store
from gendex_envs.task_version import TaskVersion
from generator.catalog_view import asset_dicts
from generator.command_wording import wordings
from generator.embedding import embed, embed_each
from generator.instruction import SYNONYMS
from generator.novelty import NEAR_DUPLICATE_COSINE
from generator.phrasing import (
    LEGACY_SITUATIONS,
    NAMES,
    PURPOSES,
    PURPOSES_DIRECTED,
    SITUATIONS,
    SITUATIONS_DIRECTED,
    Frame,
    Part,
    framings,
    phrase_parts,
    purposes,
    split,
)
from generator.reword import (
    MAX_PAIR_COSINE,
    MAX_REUSE,
    PROPOSAL_WORDINGS,
    LibraryWording,
    ProposalWording,
    RewordError,
    candidates_for,
    plan_rewording,
    publish_reworded,
    replace_instruction,
    spec_frames,
)
from generator.stats import latest_versions

ASSETS = {a["id"]: a for a in asset_dicts()}
PLANNED = 24
"""Tasks the planning test rewords (of the library's lift, put, set and close tasks)."""


def _mean_cos(texts: list[str]) -> float:
    e = embed(texts)[0]
    s = e @ e.T
    return float((s.sum() - np.trace(s)) / (len(texts) * (len(texts) - 1)))


def _without_instruction(text: str) -> list[str]:
    """The spec's lines without its header comment and its top-level instruction entry (however many lines)."""
    out, skipping = [], False
    for line in text.splitlines():
        if line.startswith("instruction:"):
            skipping = True
            continue
        if skipping and line[:1] in (" ", ""):
            continue
        skipping = False
        if not line.startswith("#"):
            out.append(line)
    return out


def test_every_sentence_the_author_writes_splits_into_its_command_and_is_one_of_its_framings():
    parts_list = [[Part("put_in", ASSETS["lemon"], ASSETS["pot"])], [Part("lift", ASSETS["tuna_can"])],
                  [Part("close_door", ASSETS["refrigerator_left_hinge"])],
                  [Part("close_lid", ASSETS["trash_can_small"]), Part("place_on", ASSETS["plum"], ASSETS["plate"])]]
    for parts in parts_list:
        for seed in range(25):
            text = phrase_parts(parts, np.random.default_rng(seed))
            situation, command, purpose = split(text)
            assert command and command[0].islower() and not command.endswith("."), text
            first, last = Frame.of(parts[0]), Frame.of(parts[-1])
            surfaces = [w for w in ("tabletop", "table", "counter", "worktop") if w in text] or ["table"]
            assert text in framings(command, first, last, surfaces[0]), text


def test_a_closing_is_never_given_a_reason_to_open_and_no_frame_names_a_catalog_object():
    fridge = Part("close_door", ASSETS["refrigerator_left_hinge"])
    for seed in range(40):
        _, _, purpose = split(phrase_parts([fridge], np.random.default_rng(seed)))
        assert purpose is None or purpose not in PURPOSES_DIRECTED[("cold", "open")]
    assert not set(purposes(Frame("box", "close"))) & set(PURPOSES_DIRECTED[("box", "open")])
    words = set(SYNONYMS) | {w for ws in NAMES.values() for w in ws} | {a["category"].replace("_", " ")
                                                                         for a in ASSETS.values()}
    pools = [*SITUATIONS.values(), *SITUATIONS_DIRECTED.values(), *PURPOSES.values(), *PURPOSES_DIRECTED.values()]
    for text in (t for pool in pools for t in pool):
        plain = re.sub(r"\bcan (be|go|start|continue|see)\b", "", text.lower())  # the verb, not the tin
        found = [w for w in words if re.search(rf"\b{re.escape(w)}s?\b", plain)]
        assert not found, (text, found)  # the reader would take them for objects of the task
    assert all(t not in pool for t in LEGACY_SITUATIONS for pool in SITUATIONS.values())


def test_replacing_the_instruction_keeps_every_other_byte(task_version):
    source = task_version("CloseCabinetRightHingeThenSetBlockMediumOnTray", 0)
    text = source.files.spec.read_text()
    new = "A new: wording, with 'quotes' and a colon."
    out = replace_instruction(text, new)
    assert yaml.safe_load(out) == dict(yaml.safe_load(text), instruction=new)
    assert _without_instruction(out) == _without_instruction(text)
    assert f"# {new}\n" in out  # the header comment that repeated the old instruction follows it
    with pytest.raises(RewordError, match="no top-level 'instruction'"):
        replace_instruction("name: X\n", new)


def test_a_reworded_task_is_published_as_the_next_version_and_the_source_is_untouched(task_copy):
    source = task_copy("LiftLemon", as_name="ScratchLemon")
    digest = source.file_digest()
    new = "Market day left produce everywhere: raise the lemon clear of the counter and keep hold of it."
    published = publish_reworded(source, new, {"reason": "test"})
    assert published.version == source.version + 1 and published.spec.instruction == new
    assert source.file_digest() == digest and source.spec.instruction != new
    record = published.provenance()["reword"]
    assert record["source"] == source.env_id and record["old"] == source.spec.instruction and record["new"] == new
    assert published.provenance()["solvability"] == source.provenance()["solvability"]  # the same scene
    spec_a, spec_b = yaml.safe_load(source.files.spec.read_text()), yaml.safe_load(published.files.spec.read_text())
    assert dict(spec_a, instruction=new) == spec_b
    assert source.files.reward.read_bytes() == published.files.reward.read_bytes()
    assert not list((source.tasks_root / ".drafts").glob("*"))  # nothing half-written left behind


def test_planning_lowers_the_librarys_mean_cosine_keeps_commands_and_caps_reuse(committed_tasks):
    # the library as it was before its rewording: the latest version of each task that is not a rewording
    unworded = {k: v for k, v in committed_tasks.items() if "reword" not in v.provenance()}
    candidates = {k: v for k, v in latest_versions(unworded).items()
                  if v.name.startswith(("Lift", "Put", "SetFoam", "Close"))}
    # a fixed number of them (the kept task and the first others by id), so the test does not grow with the library
    others = sorted(k for k, v in candidates.items() if v.name != "PutAppleBowl")[:PLANNED - 1]
    kept = [k for k, v in candidates.items() if v.name == "PutAppleBowl"]
    versions = {k: candidates[k] for k in sorted(others + kept)}
    assert len(versions) == PLANNED
    keep = {"PutAppleBowl"}
    changes, numbers = plan_rewording(versions, keep=keep)
    assert changes and numbers["mean_pairwise_cosine_after"] < numbers["mean_pairwise_cosine_before"] - 0.03
    final = {k: v.spec.instruction for k, v in versions.items()} | {c.env_id: c.new for c in changes}
    assert abs(_mean_cos(list(final.values())) - numbers["mean_pairwise_cosine_after"]) < 1e-4
    for c in changes:
        assert versions[c.env_id].name not in keep
        assert split(c.new)[1].lower() == split(c.old)[1].lower()  # what the task asks for is unchanged
    used: dict[str, int] = {}
    for text in final.values():
        sit, _, purp = split(text)
        for x in (sit, purp):
            if x is not None:
                used[x] = used.get(x, 0) + 1
    assert max(used.values()) <= MAX_REUSE
    e = embed(list(final.values()))[0]
    pairs = e @ e.T
    np.fill_diagonal(pairs, 0.0)
    assert pairs.max() < MAX_PAIR_COSINE  # no two tasks framed so that they read as one


def test_reworded_commands_read_as_the_same_tasks_and_read_less_alike(committed_tasks):
    """With commands, the command itself may change, but only to a wording the reader reads as the same task; the
    commands of the planned library then read less alike."""
    from generator.command_wording import reading_key
    from generator.instruction import read_instruction

    latest = latest_versions(committed_tasks)
    ids = sorted(k for k, v in latest.items() if v.name.startswith(("Put", "Set", "Close", "Lift")))[:12]
    versions = {k: latest[k] for k in ids}
    changes, numbers = plan_rewording(versions, commands=True, limit=40)
    assert numbers["commands_reworded"] > 0
    assert numbers["commands_mean_pairwise_cosine_after"] < numbers["commands_mean_pairwise_cosine_before"] - 0.02
    assets = list(ASSETS.values())
    moved = [c for c in changes if split(c.new)[1] != split(c.old)[1]]
    assert len(moved) == numbers["commands_reworded"]
    for c in moved:
        assert c.new[0].isupper() and c.new.endswith("."), c.new  # a sentence, as every framing is
        old, new = split(c.old)[1], split(c.new)[1]
        assert reading_key(read_instruction(new, assets)) == reading_key(read_instruction(old, assets)), c
    final = {k: v.spec.instruction for k, v in versions.items()} | {c.env_id: c.new for c in changes}
    assert abs(_mean_cos([split(t)[1] for t in final.values()])
               - numbers["commands_mean_pairwise_cosine_after"]) < 1e-4


def test_the_offline_author_words_a_proposal_least_like_the_library(task_version, committed_tasks):
    # the library without the task itself (its own instruction is in no option's way then)
    library = [v.spec.instruction for v in latest_versions(committed_tasks).values() if v.name != "PutPlumInPot"]
    spec = task_version("PutPlumInPot").spec
    proposal = {"name": "PutPlumInPot", "description": spec.instruction,
                "objects": [{"name": o.name, "asset": o.asset, "role": "graspable"} for o in spec.objects],
                "steps": [], "success": {"type": "inside", "object": "plum", "target": "pot"}}
    worded = ProposalWording()(proposal, library)
    # the command first: of its wordings the reader reads as the same task, the least like the library's commands
    command = split(spec.instruction)[1]
    commands = wordings(command, list(ASSETS.values()), limit=PROPOSAL_WORDINGS)
    assert len(commands) > 1
    chosen = LibraryWording(split(t)[1] for t in library)(commands)
    assert split(worded["description"])[1] == chosen
    options = candidates_for("PutPlumInPot", spec.instruction, spec_frames(spec), command=chosen)
    sims = embed(options)[0] @ embed_each(library)[0].T
    apart = [k for k in range(len(options)) if sims[k].max() < MAX_PAIR_COSINE]
    assert apart  # some framing reads like no task of the library
    assert worded["description"] == options[min(apart, key=lambda k: sims[k].mean())]
    assert worded["description"] == LibraryWording(library)(options)
    assert ProposalWording()(proposal, []) is proposal


def test_the_author_frames_no_proposal_with_a_situation_the_library_already_uses_twice(task_version, monkeypatch):
    """A batch of eight framed three of its tasks with one situation (the author chose against the library by the
    mean alone); a situation the library has used MAX_REUSE times is not offered again."""
    spec = task_version("PutPlumInPot").spec
    proposal = {"name": "PutPlumInPot", "description": spec.instruction,
                "objects": [{"name": o.name, "asset": o.asset, "role": "graspable"} for o in spec.objects],
                "steps": [], "success": {"type": "inside", "object": "plum", "target": "pot"}}
    favourite = "A still-life painter is arranging a scene"  # a fruit situation: offered for the plum
    # a chooser that takes the favourite whenever it is offered (the embedding did, three times in one batch)
    monkeypatch.setattr(LibraryWording, "__call__", lambda self, options: next(
        (o for o in options if o.startswith(favourite)), options[0]))
    library = ["Close the drawer.", f"{favourite}: lift the golf ball."]
    assert ProposalWording()(proposal, library)["description"].startswith(favourite)  # used once: offered
    library.append(f"{favourite}: set the pear on the plate.")
    assert not ProposalWording()(proposal, library)["description"].startswith(favourite)  # twice: not again


def test_the_author_proposes_of_the_tasks_drawn_the_one_least_like_the_library(task_version):
    """Of the few tasks of one skill the author draws, it proposes the one whose command the library says least
    (a library of bowls gets the pot), whatever the order drawn, worded as it would be alone."""
    def proposal(name, target):
        spec = task_version(name).spec
        return {"name": name, "description": spec.instruction,
                "objects": [{"name": o.name, "asset": o.asset, "role": "graspable"} for o in spec.objects],
                "steps": [], "success": {"type": "inside", "object": spec.objects[0].name, "target": target}}

    pot, bowl = proposal("PutPlumInPot", "pot"), proposal("PutAppleBowl", "bowl")
    library = ["Put the pear into the bowl.", "Drop the lemon in the bowl.", "Place the peach inside the bowl.",
               "Close the drawer."]
    author = ProposalWording()
    assert author.least_alike([bowl, pot], library)["name"] == "PutPlumInPot"
    assert author.least_alike([pot, bowl], library)["name"] == "PutPlumInPot"
    assert author.least_alike([pot], library) == author(pot, library)
    with pytest.raises(ValueError, match="no proposals"):
        author.least_alike([], library)


def test_a_sibling_is_not_worded_like_the_task_it_is_the_sibling_of():
    """The left-hinged fridge's task proposed next to the right-hinged one's: the least-alike framing by the mean
    alone took the very frame the sibling had (cosine 0.99, and the proposal was dropped as a near-duplicate)."""
    right = "Breakfast needs something from the top shelf: pull the right-hinged fridge's door open by its handle."
    library = [right, "Put the apple into the bowl.", "Close the drawer.", "Lift the golf ball off the table."]
    command = "pull the left-hinged fridge's door open by its handle"
    options = framings(command, Frame("cold", "open"), Frame("cold", "open"), "table")
    assert any(o.startswith("Breakfast needs something") for o in options)
    chosen = LibraryWording(library)(options)
    e = embed_each([chosen, right])[0]
    assert float(e[0] @ e[1]) < MAX_PAIR_COSINE, chosen


def test_the_committed_library_reads_as_varied_as_the_issue_asks(committed_tasks):
    """The library's instruction diversity (mean pairwise MiniLM cosine of the latest versions) meets the task
    library issue's goal of <= 0.19 (RoboGen 0.191; before the rewording 0.299), and its commands alone (situations
    and purposes taken off) the task-language issue's <= 0.25 (0.335 when it was filed)."""
    texts = [v.spec.instruction for v in latest_versions(committed_tasks).values()]
    assert len(texts) >= 165 and _mean_cos(texts) <= 0.19
    assert _mean_cos([split(t)[1] for t in texts]) <= 0.25
    e = embed(texts)[0]
    pairs = e @ e.T
    np.fill_diagonal(pairs, 0.0)
    assert pairs.max() < NEAR_DUPLICATE_COSINE  # and no two of them read as the same task


def test_reword_rejects_an_unknown_task_name():
    from typer.testing import CliRunner

    from gendex.cli import app

    result = CliRunner().invoke(app, ["reword", "--keep", "NoSuchTask", "--dry-run"])
    assert result.exit_code != 0 and "NoSuchTask" in result.output


def test_a_version_that_is_not_a_folder_of_the_library_is_not_touched_by_a_failed_publish(task_copy, monkeypatch):
    source = task_copy("LiftLemon", as_name="ScratchLemonTwo")
    import generator.reword as rw

    monkeypatch.setattr(rw, "replace_instruction", lambda text, new: text)  # the rewrite silently fails
    with pytest.raises(RewordError, match="the rewritten spec reads"):
        publish_reworded(source, "Something else entirely.", {})
    assert [v.version for v in map(TaskVersion.at, source.root.parent.iterdir())] == [source.version]
    assert not list((source.tasks_root / ".drafts").glob("*"))


def test_a_reworded_version_differs_from_its_source_only_in_its_instruction(committed_tasks):
    """What lets the environment checks test a reworded version through its source: every committed rewording
    is its source's folder byte for byte, but for the spec's instruction (and its reword record)."""
    found = committed_tasks

    def derived_by_rewording(v) -> bool:
        """Its own derivation was a rewording: a version keeps the records of its source's (a revision of a reworded
        version still holds the reword record), so its own is the one whose source is newest."""
        records = v.provenance()
        if "reword" not in records:
            return False
        sources = {k: r["source"] for k, r in records.items() if isinstance(r, dict) and "source" in r}
        newest = max(sources.values(), key=lambda s: int(s.rsplit("-v", 1)[1]))
        return records["reword"]["source"] == newest

    reworded = {e: v for e, v in found.items() if derived_by_rewording(v)}
    assert len(reworded) >= 70
    for env_id, v in reworded.items():
        source = found[v.provenance()["reword"]["source"]]
        assert source.name == v.name and source.version < v.version, env_id
        files = {rel: path for rel, path, _ in task_store.files(v.root)}  # the whole version, stored files too
        src = {rel: path for rel, path, _ in task_store.files(source.root)}
        assert files.keys() - src.keys() <= {"reword.json"} and "reword.json" in files, env_id  # a source may be one
        assert src.keys() <= files.keys(), env_id
        for rel in src.keys() - {"task.yaml", "reword.json"}:
            assert files[rel].read_bytes() == src[rel].read_bytes(), (env_id, rel)
        a, b = yaml.safe_load(source.files.spec.read_text()), yaml.safe_load(v.files.spec.read_text())
        assert dict(a, instruction=b["instruction"]) == b and v.provenance()["reword"]["new"] == b["instruction"]


def test_every_committed_reworded_command_reads_as_its_sources(committed_tasks):
    """A rewording that changed the command (gendex reword --commands) changed only words: the instruction reader
    reads the new command as the same task as its source's."""
    from generator.command_wording import reading_key
    from generator.instruction import read_instruction

    assets = list(ASSETS.values())
    moved = 0
    for env_id, v in committed_tasks.items():
        record = v.provenance().get("reword")
        if record is None or split(record["old"])[1] == split(record["new"])[1]:
            continue
        moved += 1
        old, new = split(record["old"])[1], split(record["new"])[1]
        assert reading_key(read_instruction(new, assets)) == reading_key(read_instruction(old, assets)), env_id
    assert moved >= 150


def test_a_place_task_is_framed_by_the_object_it_moves():
    """A placed task's object is the one its rigid part moves: its command gets a situation and purpose like any
    set-down (before: 'no object the task acts on', and the bare command was kept)."""
    from generator.backends.offline import OfflineBackend
    from generator.reword import proposal_frames

    options = OfflineBackend(seed=1).task_options(list(asset_dicts()))
    placed = next(raw for kind, raw in options if kind == "place_at")
    first, last = proposal_frames(placed)
    assert first == last and first.domain and first.direction is None  # the moved object's domain


def test_every_task_of_the_library_has_frames_to_be_reworded_by(committed_tasks):
    """``gendex reword`` frames every task by what it acts on: a press switches its button on and a twist
    unscrews its cap, as an open does (before: 'PressButtonArcade: no object the task acts on', and the command
    stopped for the whole library)."""
    from generator.phrasing import direction
    from generator.reword import spec_frames

    frames = {v.name: spec_frames(v.spec) for v in latest_versions(committed_tasks).values()}
    press = [f for n, f in frames.items() if n.startswith(("Press", "Unscrew"))]
    assert press and all(first.direction == direction("press") == direction("twist") == "open" for first, _ in press)
