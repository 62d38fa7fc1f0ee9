"""Hostile task files, model replies and transcripts are refused with a typed error that names why (issue 17, item 4).

Each file of ``tests/data/hostile_yaml`` (and the big ones generated here into tmp_path) must raise TaskSpecError
whose message holds the named reason; an alias bomb is refused in under a second and 200 MB; a property-based fuzz of
the loader finds nothing but typed errors. Time bounds on work done in this process are on its CPU time
(``time.process_time``): a parser stuck on a bomb spends CPU; other work on a loaded machine does not count (a wall-
clock bound of 1 s failed at 1.08 s beside two task generations).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gendex_envs.errors import GenDexError, TaskSpecError
from gendex_envs.spec import dump_task_spec, load_task_spec, parse_task_spec
from gendex_envs.typed_yaml import (
    MAX_DEPTH,
    MAX_INPUT_BYTES,
    MAX_NODES,
    MAX_OBJECTS,
    MAX_STRING_CHARS,
    QUOTE_CHARS,
    load_yaml_bounded,
    quote,
)
from generator.backends.transcript import ReplayBackend
from generator.errors import ProposalError, SceneError, TranscriptMismatchError
from generator.steps.common import parse_json_block, parse_yaml_block

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data" / "hostile_yaml"
REFERENCE = ROOT / "generated_tasks" / "PutAppleBowl" / "v1" / "task.yaml"
MAX_MESSAGE = 1024
"""Longest error message any hostile input may produce (the issue measured a 3 GB one)."""

HOSTILE: dict[str, str] = {
    "alias_bomb.yaml": "more than 20000 nodes",
    "alias_deep.yaml": "nesting deeper than 32 levels",
    "alias_undefined.yaml": "found undefined alias",
    "recursive_alias.yaml": "recursive alias *loop",
    "python_object_apply.yaml": "tag 'tag:yaml.org,2002:python/object/apply:os.system' is not allowed",
    "python_name.yaml": "tag 'tag:yaml.org,2002:python/name:os.system' is not allowed",
    "python_module.yaml": "tag 'tag:yaml.org,2002:python/module:subprocess' is not allowed",
    "custom_tag.yaml": "tag '!shell' is not allowed",
    "binary_tag.yaml": "tag 'tag:yaml.org,2002:binary' is not allowed",
    "set_tag.yaml": "tag 'tag:yaml.org,2002:set' is not allowed",
    "invalid_utf8.yaml": "is not UTF-8 text",
    "binary_garbage.yaml": "unacceptable character",
    "duplicate_keys.yaml": "duplicate key 'name'",
    "merge_key.yaml": "merge keys (<<) are not allowed",
    "nan_pose.yaml": "objects[0].pos_m[0] = nan is not allowed; must be a finite number",
    "nan_quaternion.yaml": "objects[0].quat_wxyz[0] = nan is not allowed; must be a finite number",
    "inf_scale.yaml": "objects[1].scale = inf is not allowed; must be a finite number",
    "overflow_float.yaml": "objects[1].pos_m[0] = inf is not allowed; must be a finite number",
    "huge_int.yaml": "is out of range; integers must lie within +/-2**63",
    "huge_steps.yaml": "max_episode_steps = 9000000000000 is not allowed; must be >= 1 and <= 100000",
    "sexagesimal_overflow.yaml": "is out of range",
    "objects_65.yaml": "objects: 65 objects; at most 64 are allowed",
    "giant_string.yaml": "a value of 5699 characters; at most 4096 are allowed",
    "long_unknown_key.yaml": "unknown key 'kkkk",
    "multi_document.yaml": "expected a single document",
    "top_level_list.yaml": "top level: expected a mapping",
    "empty.yaml": "the file is empty",
    "wrong_type_bool.yaml": "stages[0].horizon = True has the wrong type (bool)",
}


def _refused(path: Path, reason: str) -> str:
    with pytest.raises(TaskSpecError) as info:
        load_task_spec(path)
    msg = str(info.value)
    assert reason in msg, msg
    assert len(msg) <= MAX_MESSAGE, f"{len(msg)} characters: {msg[:300]}"
    return msg


def test_every_committed_hostile_file_has_a_named_reason():
    assert sorted(p.name for p in DATA.glob("*.yaml")) == sorted(HOSTILE)
    assert len(HOSTILE) >= 15


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_hostile_file_is_refused_with_its_reason(name):
    _refused(DATA / name, HOSTILE[name])


def test_the_alias_bomb_is_small():
    assert (DATA / "alias_bomb.yaml").stat().st_size <= 1600


def test_alias_bomb_is_refused_fast_and_small_in_process():
    tracemalloc.start()
    try:
        start = time.process_time()
        _refused(DATA / "alias_bomb.yaml", "more than 20000 nodes")
        elapsed = time.process_time() - start
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert elapsed < 1.0, f"{elapsed:.3f} s"
    assert peak < 200 * 2**20, f"{peak / 2**20:.1f} MB"


@pytest.mark.skipif(not Path("/proc/self/status").is_file(), reason="reads VmHWM from /proc (Linux)")
def test_alias_bomb_is_refused_fast_and_small_in_a_fresh_process():
    """The whole child (interpreter, numpy, the loader) stays under 200 MB resident; the refusal under a second.
    The child reads its own high-water mark, VmHWM (Linux): RUSAGE_CHILDREN here would be the largest of every child
    any earlier test started, and the child's RUSAGE_SELF keeps the RSS this process had when it forked."""
    code = (
        "import json, sys, time\n"
        "from gendex_envs.errors import TaskSpecError\n"
        "from gendex_envs.spec import load_task_spec\n"
        "start = time.perf_counter()\n"
        "try:\n"
        "    load_task_spec(sys.argv[1])\n"
        "    kind = 'loaded'\n"
        "except TaskSpecError:\n"
        "    kind = 'TaskSpecError'\n"
        "peak = next(int(line.split()[1]) for line in open('/proc/self/status') if line.startswith('VmHWM:'))\n"
        "print(json.dumps({'kind': kind, 'seconds': time.perf_counter() - start, 'peak_kib': peak}))\n"
    )
    out = subprocess.run([sys.executable, "-c", code, str(DATA / "alias_bomb.yaml")], cwd=ROOT, capture_output=True,
                         text=True, timeout=120, check=True)
    result = json.loads(out.stdout.strip().splitlines()[-1])
    peak_mb = result["peak_kib"] / 1024
    assert result["kind"] == "TaskSpecError"
    assert result["seconds"] < 1.0, result
    assert peak_mb < 200, f"{peak_mb:.0f} MB"


def test_committed_tasks_with_plain_anchors_still_load():
    """Anchors are capped, not banned: 11 committed tasks repeat a condition with &name / *name."""
    with_alias = [p for p in sorted((ROOT / "generated_tasks").glob("*/v*/task.yaml")) if "*" in p.read_text()]
    assert with_alias
    for path in with_alias:
        load_task_spec(path)


# ------------------------------------------------------------------------------ big inputs made in tmp_path
def _reference_tail() -> str:
    text = REFERENCE.read_text()
    return text[text.index("stages:"):]


def test_object_flood_of_full_objects_is_refused_before_parsing(tmp_path):
    path = tmp_path / "flood.yaml"
    objects = "".join(f"  - {{name: o{i}, asset: apple, pos_m: [0.0, 0.0, 0.0]}}\n" for i in range(150_000))
    path.write_text("name: Flood\ninstruction: x\nobjects:\n" + objects + _reference_tail())
    start = time.process_time()
    _refused(path, f"at most {MAX_INPUT_BYTES} bytes are allowed")
    assert time.process_time() - start < 1.0


def test_object_flood_under_the_size_bound_is_refused_by_the_node_ceiling(tmp_path):
    path = tmp_path / "flood.yaml"
    path.write_text("name: Flood\ninstruction: x\nobjects: [" + "{}, " * 150_000 + "]\n")
    assert path.stat().st_size < MAX_INPUT_BYTES
    start = time.process_time()
    _refused(path, f"more than {MAX_NODES} nodes")
    assert time.process_time() - start < 5.0


def test_object_flood_in_a_mapping_is_refused_before_any_object_is_built():
    raw = yaml.safe_load(REFERENCE.read_text())
    raw["objects"] = [dict(raw["objects"][0], name=f"o{i}") for i in range(150_000)]
    start = time.process_time()
    with pytest.raises(TaskSpecError, match=r"objects: 150000 objects; at most 64 are allowed"):
        parse_task_spec(raw, "flood")
    assert time.process_time() - start < 1.0


@pytest.mark.parametrize("key,items,limit", [("stages", "stages", 32), ("conditions", "conditions", 32)])
def test_stage_and_condition_lists_have_ceilings(key, items, limit):
    raw = yaml.safe_load(REFERENCE.read_text())
    if key == "stages":
        raw["stages"] = [dict(raw["stages"][0], name=f"s{i}") for i in range(limit + 1)]
        where = "stages"
    else:
        raw["success"]["conditions"] = raw["success"]["conditions"] * (limit + 1)
        where = "success.conditions"
    with pytest.raises(TaskSpecError, match=rf"{where}: {limit + 1} {items}; at most {limit} are allowed"):
        parse_task_spec(raw, "many")


def test_sixty_four_objects_are_allowed():
    raw = yaml.safe_load(REFERENCE.read_text())
    raw["objects"] += [dict(raw["objects"][0], name=f"o{i}", distractor=True) for i in range(MAX_OBJECTS - 2)]
    assert len(parse_task_spec(raw, "many").objects) == MAX_OBJECTS


def test_file_over_one_megabyte_is_refused_before_parsing(tmp_path):
    path = tmp_path / "big.yaml"
    path.write_text(REFERENCE.read_text() + "#" * MAX_INPUT_BYTES + "\n")
    _refused(path, "is larger than 1000000 bytes; at most 1000000 bytes are allowed")


@pytest.mark.parametrize("open_,close", [("[", "]"), ("{a: ", "}")])
def test_ten_thousand_deep_nesting_is_refused(tmp_path, open_, close):
    path = tmp_path / "deep.yaml"
    path.write_text("name: " + open_ * 10_000 + "1" + close * 10_000 + "\n")
    start = time.process_time()
    _refused(path, f"nesting deeper than {MAX_DEPTH} levels")
    assert time.process_time() - start < 2.0


def test_deep_block_nesting_is_refused(tmp_path):
    path = tmp_path / "deep.yaml"
    path.write_text("".join(" " * i + f"k{i}:\n" for i in range(1000)) + " " * 1000 + "v\n")
    _refused(path, f"nesting deeper than {MAX_DEPTH} levels")


def test_list_where_a_mapping_is_expected_quotes_little_of_it(tmp_path):
    path = tmp_path / "list.yaml"
    path.write_text(REFERENCE.read_text() + "robot:\n" + "".join(f"  - {'x' * 4000}{i}\n" for i in range(200)))
    msg = _refused(path, "robot = ")
    assert "has the wrong type (list)" in msg
    assert "x" * (QUOTE_CHARS + 1) not in msg


def test_giant_string_from_a_mapping_is_refused_and_clipped():
    raw = yaml.safe_load(REFERENCE.read_text())
    raw["instruction"] = "y" * 100_000
    with pytest.raises(TaskSpecError) as info:
        parse_task_spec(raw, "giant")
    msg = str(info.value)
    assert f"at most {MAX_STRING_CHARS} characters" in msg and len(msg) <= MAX_MESSAGE
    assert "y" * (QUOTE_CHARS + 1) not in msg


def test_quote_cuts_long_values():
    assert len(quote("z" * 10_000)) <= QUOTE_CHARS + 40
    assert len(quote(list(range(100_000)))) <= QUOTE_CHARS + 3
    assert quote("abc") == "'abc'"


def test_round_trip_through_the_bounded_loader():
    spec = load_task_spec(REFERENCE)
    assert parse_task_spec(yaml.safe_load(dump_task_spec(spec))) == spec
    assert parse_task_spec(load_yaml_bounded(dump_task_spec(spec), "dump")) == spec


# ------------------------------------------------------------------------------ model replies and transcripts
BOMB = (DATA / "alias_bomb.yaml").read_text()


@pytest.mark.parametrize("reply,reason", [
    (f"```yaml\n{BOMB}```", "more than 20000 nodes"),
    ("```yaml\nname: !!python/object/apply:os.system [ls]\n```", "is not allowed"),
    ("```yaml\nname: " + "[" * 5000 + "]" * 5000 + "\n```", "nesting deeper than 32 levels"),
    ("```yaml\nname: " + "w" * 5000 + "\n```", "a value of 5000 characters"),
    ("```yaml\na: 1\na: 2\n```", "duplicate key 'a'"),
    ("```yaml\n" + "# pad\n" * 200_000 + "a: 1\n```", "at most 1000000 bytes are allowed"),
])
def test_model_yaml_reply_bounds(reply, reason):
    start = time.process_time()
    with pytest.raises(SceneError) as info:
        parse_yaml_block(reply, "scene file", SceneError)
    assert reason in str(info.value) and len(str(info.value)) <= MAX_MESSAGE
    assert time.process_time() - start < 1.0


@pytest.mark.parametrize("reply,reason", [
    ("```json\n" + "[" * 100_000 + "]" * 100_000 + "\n```", "nesting deeper than"),
    ('```json\n{"a": 1, "a": 2}\n```', "duplicate key 'a'"),
    ('```json\n{"a": ' + "9" * 5000 + "}\n```", "is out of range"),
    ('```json\n{"a": NaN}\n```', "NaN is not allowed"),
    ('```json\n{"a": "' + "v" * 5000 + '"}\n```', "a value of 5000 characters"),
    ("```json\n[" + "0," * 30_000 + "0]\n```", "more than 20000 nodes"),
    ("```json\n[" + " " * 1_100_000 + "]\n```", "at most 1000000 bytes are allowed"),
])
def test_model_json_reply_bounds(reply, reason):
    with pytest.raises(ProposalError) as info:
        parse_json_block(reply, "proposal", ProposalError)
    assert reason in str(info.value) and len(str(info.value)) <= MAX_MESSAGE


def _transcript(tmp_path: Path, lines: list[str]) -> Path:
    header = json.dumps({"header": {"format": "gendex-transcript", "version": 2, "backend": "anthropic",
                                    "model": "m", "sees_images": False, "is_language_model": True}})
    path = tmp_path / "transcript.jsonl"
    path.write_text("\n".join([header, *lines]) + "\n")
    return path


def _exchange(i: int, text: str = "ok") -> str:
    return json.dumps({"index": i, "step": "propose", "digest": "d", "request": {},
                       "response": {"text": text, "backend": "anthropic", "model": "m"}})


@pytest.mark.parametrize("lines,reason", [
    (['{"index": 0, "step": "s", "digest": "d", "request": ' + "[" * 50_000 + "]" * 50_000 + "}"],
     "nesting deeper than"),
    ([_exchange(0, "r" * (MAX_INPUT_BYTES + 1))], "the recorded reply is 1000001 bytes"),
    ([_exchange(i) for i in range(10_001)], "more than 10000 exchanges"),
    (['{"index": 0, "index": 0}'], "duplicate key 'index'"),
])
def test_transcript_bounds(tmp_path, lines, reason):
    path = _transcript(tmp_path, lines)
    start = time.process_time()
    with pytest.raises(TranscriptMismatchError) as info:
        ReplayBackend(path)
    assert reason in str(info.value) and len(str(info.value)) <= MAX_MESSAGE
    assert time.process_time() - start < 5.0


@pytest.mark.parametrize("loader", ["suite", "manifest"])
def test_suite_and_dataset_manifest_files_are_bounded_too(tmp_path, loader):
    from gendex.data.datasets import DatasetError, load_manifest
    from gendex.eval.suite import SuiteError, load_suite

    path = tmp_path / "hostile.yaml"
    path.write_text(BOMB)
    load, error = (load_suite, SuiteError) if loader == "suite" else (load_manifest, DatasetError)
    start = time.process_time()
    with pytest.raises(error, match="more than 20000 nodes"):
        load(path)
    assert time.process_time() - start < 1.0


def test_a_committed_transcript_still_replays():
    from gendex_envs.registry import REPO_TASKS_DIR
    from gendex_envs.task_version import versions_in

    path = next((v.files.resolve(v.files.transcript) for v in versions_in(REPO_TASKS_DIR)
                 if v.files.resolve(v.files.transcript).is_file()), None)
    assert path is not None, "the generated tasks ship their transcripts"
    assert len(ReplayBackend(path)) > 0


# ------------------------------------------------------------------------------ property-based fuzz
_REFERENCE_TEXT = REFERENCE.read_text()
_REFERENCE_RAW = yaml.safe_load(_REFERENCE_TEXT)
_YAMLISH = st.text(alphabet=st.sampled_from(list("abcxyz019 .-_:,[]{}&*!|>'\"#%@`<?=~\n\t\\") + ["\x00", "\u00e9",
                                                                                               "\ufeff", "\ud800"]),
                   max_size=200)
_SCALARS = st.one_of(st.none(), st.booleans(), st.integers(), st.floats(allow_nan=True, allow_infinity=True),
                     st.text(max_size=30))
_TREES = st.recursive(_SCALARS, lambda kids: st.one_of(st.lists(kids, max_size=5),
                                                       st.dictionaries(st.text(max_size=12), kids, max_size=5)),
                      max_leaves=40)
_KEYS = st.sampled_from(["name", "instruction", "objects", "stages", "success", "table", "robot", "goal", "pos_m",
                         "scale", "quat_wxyz", "asset", "conditions", "type", "object", "target", "horizon",
                         "skill", "method", "randomize", "max_episode_steps", "joint_state", "<<", "x"])


def _paths(value, prefix=()):
    yield prefix
    if isinstance(value, dict):
        for k, v in value.items():
            yield from _paths(v, (*prefix, k))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from _paths(v, (*prefix, i))


_REFERENCE_PATHS = list(_paths(_REFERENCE_RAW))[1:]


@st.composite
def _mutated_reference(draw) -> str:
    """The reference task with a few values replaced, keys added or dropped, lists grown, or its text edited."""
    raw = json.loads(json.dumps(_REFERENCE_RAW))
    for _ in range(draw(st.integers(1, 4))):
        path = draw(st.sampled_from(_REFERENCE_PATHS))
        parent = raw
        try:
            for step in path[:-1]:
                parent = parent[step]
            op = draw(st.sampled_from(["replace", "drop", "add", "grow"]))
            if op == "replace":
                parent[path[-1]] = draw(_TREES)
            elif op == "drop" and isinstance(parent, dict):
                del parent[path[-1]]
            elif op == "add" and isinstance(parent, dict):
                parent[draw(_KEYS)] = draw(_TREES)
            elif op == "grow" and isinstance(parent[path[-1]], list):
                parent[path[-1]] = parent[path[-1]] * draw(st.integers(2, 70))
        except (KeyError, IndexError, TypeError):
            pass
    text = yaml.safe_dump(raw, allow_unicode=True, sort_keys=False)
    if draw(st.booleans()):  # text-level edits: splice YAML-ish fragments in at random places
        for _ in range(draw(st.integers(1, 3))):
            at = draw(st.integers(0, len(text)))
            cut = draw(st.integers(0, 20))
            text = text[:at] + draw(_YAMLISH) + text[at + cut:]
    return text


def _fuzz_texts():
    return st.one_of(
        _YAMLISH,
        _TREES.map(lambda t: yaml.safe_dump(t, allow_unicode=True)),
        _mutated_reference(),
        _mutated_reference(),
    )


@pytest.fixture(scope="module")
def fuzz_file(tmp_path_factory) -> Path:
    """The file each fuzz case is written to (module-scoped: hypothesis runs many cases per test call)."""
    return tmp_path_factory.mktemp("fuzz") / "task.yaml"


def _check_one(text: str, path: Path) -> None:
    try:
        path.write_bytes(text.encode("utf-8", "surrogatepass"))
    except UnicodeEncodeError:
        return
    start = time.process_time()
    try:
        spec = load_task_spec(path)
    except GenDexError as e:
        assert len(str(e)) <= 8 * MAX_MESSAGE, str(e)[:500]
    else:
        again = parse_task_spec(load_yaml_bounded(dump_task_spec(spec), "round trip"))
        assert again == spec
        assert all(math.isfinite(v) for o in spec.objects for v in (*o.pos_m, o.scale))
    assert time.process_time() - start < 2.0


FUZZ_CASES = 10_000
"""Cases of the full spec-loader fuzz (issue 17 asks for at least 10 000; about 80 s here, so marked slow)."""
FUZZ_CASES_QUICK = 500
"""Cases of the fuzz in the default suite (about 10 s)."""
_FUZZ = dict(derandomize=True, database=None, deadline=None, print_blob=True,
             suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much, HealthCheck.data_too_large])


@settings(max_examples=FUZZ_CASES_QUICK, **_FUZZ)
@given(text=_fuzz_texts())
def test_fuzz_the_spec_loader_finds_only_typed_errors(fuzz_file, text):
    _check_one(text, fuzz_file)


@pytest.mark.slow
@settings(max_examples=FUZZ_CASES, **_FUZZ)
@given(text=_fuzz_texts())
def test_fuzz_the_spec_loader_ten_thousand_cases(fuzz_file, text):
    _check_one(text, fuzz_file)
