"""What runs is what was checked (issue 43, class "what runs is not what was checked").

A reward module is read once, strictly as UTF-8; that text is checked, compiled and executed. Nothing is imported
from the task folder, so an encoding declaration, a byte-order mark or a bytecode cache shipped in the folder
cannot change what runs.

Every payload in ``tests/data/hostile_r2/loading`` starts with ``# expect: <text>``, a substring of the refusal.
Payloads that succeed run code that switches the runtime guard off (``getattr.__globals__`` is the guard's
module), so all loads run in one fresh interpreter and report back.
"""

from __future__ import annotations

import codecs
import json
import os
import subprocess
import sys
import textwrap
import tokenize
from io import BytesIO
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gendex_envs.code_check.source import decode_reward_source
from gendex_envs.errors import RewardCodeError, UnsafeCodeError

REPO = Path(__file__).resolve().parents[2]
CORPUS = sorted((REPO / "tests" / "data" / "hostile_r2" / "loading").glob("*.py"))

BENIGN = '''import torch

REWARD_MAX = 1.0


def evaluate(env):
    return {"fail": torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)}


def compute_dense_reward(env, obs, action, info):
    return torch.zeros(env.num_envs, device=env.device)
'''
BENIGN_BYTES = BENIGN.encode()

ESCAPE = '''g = getattr.__globals__
g["_untrusted"] = ()
g["builtins"].open(MARKER, "w").write("pwned")
'''
"""Untrusted code that got past every check: the restricted ``getattr`` is the guard's function, so its globals
are the guard's state; emptying ``_untrusted`` switches the audit hook off, and then it writes a file."""

UNCHECKED_PYC = ESCAPE + BENIGN.replace("REWARD_MAX = 1.0", "REWARD_MAX = 7.0")

BINARY = {  # name -> (bytes, expected substring)
    "utf16_le_bom": (codecs.BOM_UTF16_LE + BENIGN.encode("utf-16-le"), "UTF-16-LE byte-order mark"),
    "utf16_be_bom": (codecs.BOM_UTF16_BE + BENIGN.encode("utf-16-be"), "UTF-16-BE byte-order mark"),
    "utf32_le_bom": (codecs.BOM_UTF32_LE + BENIGN.encode("utf-32-le"), "UTF-32-LE byte-order mark"),
    "latin1_byte": (b"# caf\xe9\n" + BENIGN_BYTES, "line 1: byte 5 (b'\\xe9') is not valid UTF-8"),
    "overlong_slash": (BENIGN_BYTES + b"# \xc0\xaf\n", "is not valid UTF-8"),
    "surrogate": (BENIGN_BYTES + b"# \xed\xa0\x80\n", "is not valid UTF-8"),
    "utf8_bom_then_latin1_cookie": (codecs.BOM_UTF8 + b"# coding: latin-1\n" + BENIGN_BYTES,
                                    "latin-1` is not allowed"),
}
ACCEPTED = {  # spellings of UTF-8 that load, with what they must load as
    "cookie_utf8": b"# -*- coding: utf-8 -*-\n" + BENIGN_BYTES,
    "cookie_UTF8": b"#!/usr/bin/env python\n# coding=UTF8\n" + BENIGN_BYTES,
    "cookie_utf_8_vim": b"# vim: set fileencoding=utf_8 :\n" + BENIGN_BYTES,
    "utf8_bom": codecs.BOM_UTF8 + BENIGN_BYTES,
    "utf8_text": "# Grüße, 力\n".encode() + BENIGN_BYTES,
}

SCRIPT = r'''
import json, os, sys
from gendex_envs import guard
from gendex_envs.reward_module import load_reward_module
cases = json.loads(sys.argv[1])
guard.untrust(sys.argv[2])  # a folder the guard watches: it stays watched unless its state is reached
out = {}
for case in cases:
    try:
        module = load_reward_module(case["path"], trusted=case["trusted"], static_check=case["static_check"])
        out[case["id"]] = {"loaded": True, "reward_max": module.reward_max}
    except Exception as e:
        out[case["id"]] = {"loaded": False, "error": type(e).__name__ + ": " + str(e)}
    out[case["id"]]["marker"] = os.path.exists(case["marker"])
    out[case["id"]]["guard_intact"] = any(f.startswith(sys.argv[2]) for f in guard.untrusted_folders())
print("RESULT " + json.dumps(out))
'''


def _header(path: Path) -> str:
    line = path.read_bytes().split(b"\n", 1)[0].decode()
    assert line.startswith("# expect: "), path.name
    return line.removeprefix("# expect: ").split("  #")[0]  # `# expect: reason  # more` (a cookie on line 1)


def _folder(root: Path, name: str) -> Path:
    folder = root / "tasks" / name / "v1"
    folder.mkdir(parents=True)
    return folder


def _pyc_payload(folder: Path, source: str, tmp: Path) -> None:
    """An unchecked-hash ``.pyc`` of ``source`` where the importer looks first for ``folder/reward.py``."""
    import importlib.util
    import py_compile

    payload = tmp / f"payload_{folder.parent.name}.py"
    payload.write_text(source)
    py_compile.compile(str(payload), cfile=importlib.util.cache_from_source(str(folder / "reward.py")),
                       dfile=str(folder / "reward.py"), doraise=True,
                       invalidation_mode=py_compile.PycInvalidationMode.UNCHECKED_HASH)


@pytest.fixture(scope="module")
def results(tmp_path_factory) -> dict:
    root = tmp_path_factory.mktemp("loading")
    cases = []

    def add(cid: str, data: bytes, trusted: bool, static_check: bool, expect: str | None, pyc: str | None = None):
        folder = _folder(root, cid)
        marker = root / f"marker_{cid}"
        (folder / "reward.py").write_bytes(data.replace(b"MARKER", repr(str(marker)).encode()))
        if pyc is not None:
            _pyc_payload(folder, pyc.replace("MARKER", repr(str(marker))), root)
        cases.append({"id": cid, "path": str(folder / "reward.py"), "marker": str(marker), "trusted": trusted,
                      "static_check": static_check, "expect": expect})

    for path in CORPUS:
        for static_check in (True, False):
            add(f"{path.stem}-{'static' if static_check else 'nostatic'}", path.read_bytes(), False, static_check,
                _header(path))
        add(f"{path.stem}-trusted", path.read_bytes(), True, True, _header(path))
    for name, (data, expect) in BINARY.items():
        for static_check in (True, False):
            add(f"{name}-{'static' if static_check else 'nostatic'}", data, False, static_check, expect)
    for name, data in ACCEPTED.items():
        add(f"{name}-accepted", data, False, True, None)
    add("pyc-untrusted", BENIGN_BYTES, False, True, None, pyc=UNCHECKED_PYC)
    add("pyc-untrusted-nostatic", BENIGN_BYTES, False, False, None, pyc=UNCHECKED_PYC)
    add("pyc-trusted", BENIGN_BYTES, True, True, None, pyc='open(MARKER, "w").write("pwned")\n' + BENIGN.replace(
        "REWARD_MAX = 1.0", "REWARD_MAX = 7.0"))
    add("fresh-folder", BENIGN_BYTES, False, True, None)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONDONTWRITEBYTECODE", "PYTHONPYCACHEPREFIX")}
    proc = subprocess.run([sys.executable, "-c", SCRIPT, json.dumps(cases), str(root / "watched")],
                          capture_output=True, text=True, timeout=300, cwd=REPO, env=env)
    line = next((x for x in proc.stdout.splitlines() if x.startswith("RESULT ")), None)
    assert line, proc.stdout[-2000:] + proc.stderr[-3000:]
    out = json.loads(line[7:])
    return {c["id"]: {**c, **out[c["id"]]} for c in cases}


def _refused(results: dict, prefix: str) -> list[dict]:
    found = [r for cid, r in results.items() if cid.startswith(prefix + "-")]
    assert found, prefix
    return found


@pytest.mark.parametrize("path", CORPUS, ids=lambda p: p.stem)
def test_encoding_declarations_are_refused_with_a_typed_error(results, path):
    """Statically checked or not, trusted or not: a declaration of another encoding is refused before anything
    runs, with a RewardModuleError naming the declaration and saying only UTF-8 is allowed."""
    for r in _refused(results, path.stem):
        assert not r["loaded"], r
        assert r["error"].startswith("RewardModuleError") and r["expect"] in r["error"], r
        assert "only UTF-8 is allowed" in r["error"] or "no-such-codec" in r["error"], r
        assert not r["marker"] and r["guard_intact"], r


@pytest.mark.parametrize("name", sorted(BINARY))
def test_other_encodings_and_invalid_utf8_are_refused(results, name):
    for r in _refused(results, name):
        assert not r["loaded"] and r["error"].startswith("RewardModuleError"), r
        assert r["expect"] in r["error"] and "only UTF-8 is allowed" in r["error"], r


@pytest.mark.parametrize("name", sorted(ACCEPTED))
def test_utf8_in_any_spelling_loads(results, name):
    r = results[f"{name}-accepted"]
    assert r["loaded"] and r["reward_max"] == 1.0, r


@pytest.mark.parametrize("case", ["pyc-untrusted", "pyc-untrusted-nostatic", "pyc-trusted"])
def test_a_bytecode_cache_in_the_folder_never_runs(results, case):
    """An unchecked-hash ``__pycache__/reward.cpython-*.pyc`` (the importer would run it without looking at the
    source) is ignored: the module is the checked source (REWARD_MAX 1.0, not the cache's 7.0), no marker."""
    r = results[case]
    assert r["loaded"] and r["reward_max"] == 1.0, r
    assert not r["marker"] and r["guard_intact"], r


def test_loading_writes_no_bytecode_into_the_folder(results):
    r = results["fresh-folder"]
    assert r["loaded"], r
    assert not (Path(r["path"]).parent / "__pycache__").exists()


def test_the_corpus_covers_each_kind_of_declaration():
    stems = {p.stem for p in CORPUS}
    assert {"cookie_utf7_hidden_code", "cookie_latin1_vim_line2", "cookie_latin1_line1"} <= stems


# ---------------------------------------------------------------------------------------------- fuzz
_LINE = st.one_of(
    st.sampled_from([b"# coding: latin-1", b"# -*- coding: utf-8 -*-", b"# coding=utf-7", b"#!python",
                     b"# vim: fileencoding=UTF8", b"import torch", b"", b"# coding: utf_16", b"x = 1"]),
    st.binary(max_size=24),
)


@settings(max_examples=400, deadline=None)
@given(prefix=st.sampled_from([b"", codecs.BOM_UTF8, codecs.BOM_UTF16_LE, codecs.BOM_UTF32_BE]),
       lines=st.lists(_LINE, min_size=1, max_size=4))
def test_accepted_text_is_what_the_importer_would_have_read(prefix, lines):
    """Whatever bytes are accepted decode to exactly the text Python's importer would have decoded them to
    (``tokenize.detect_encoding``, its own algorithm); everything else is refused with a typed error."""
    data = prefix + b"\n".join(lines)
    try:
        text = decode_reward_source(data, "fuzz.py")
    except UnsafeCodeError:
        return
    except RewardCodeError as exc:  # pragma: no cover - only the size limit raises the base class
        raise AssertionError(exc) from None
    encoding, _ = tokenize.detect_encoding(BytesIO(data).readline)
    assert codecs.lookup(encoding).name in ("utf-8", "utf-8-sig")
    assert data.decode(encoding) == text


def test_oversized_file_is_not_read_past_the_limit(tmp_path):
    from gendex_envs.code_check.rules import MAX_SOURCE_BYTES
    from gendex_envs.code_check.source import read_reward_source

    big = tmp_path / "reward.py"
    big.write_bytes(BENIGN_BYTES + b"#" * MAX_SOURCE_BYTES)
    with pytest.raises(RewardCodeError, match="too long for a reward module"):
        read_reward_source(big)


def test_every_module_loader_reads_through_the_strict_reader():
    """No code of GenDex imports task-folder Python from a path (the one loader compiles the checked text)."""
    offenders = []
    for package in ("gendex_envs", "gendex", "generator"):
        for path in (REPO / package).rglob("*.py"):
            text = path.read_text(encoding="utf-8")
            for needle in ("spec_from_file_location", "exec_module", "SourceFileLoader", "import runpy", "runpy.",
                           "run_path"):
                if needle in text:
                    offenders.append(f"{path.relative_to(REPO)}: {needle}")
    assert offenders == [], offenders


def test_the_corpus_payload_hides_code_from_a_utf8_reader():
    """The UTF-7 payload is real: decoded as its declaration says, the comment is code."""
    data = (REPO / "tests/data/hostile_r2/loading/cookie_utf7_hidden_code.py").read_bytes()
    assert "getattr.__globals__" not in textwrap.dedent(data.decode("utf-8")).split("\n# note")[0]
    assert "\ng = getattr.__globals__\n" in data.decode("utf-7")


_TENSOR_FROM_DATA = '''
import json, os, sys, tempfile
from pathlib import Path
os.environ["GENDEX_IN_PROCESS_GUARD"] = "1"  # the probe child's mode: untrusted code in this process
from gendex_envs.reward_module import load_reward_module
folder = Path(tempfile.mkdtemp()) / "Scratch" / "v0"
folder.mkdir(parents=True)
(folder / "reward.py").write_text(
    "import torch\\n"
    "def evaluate(env):\\n"
    "    return {'x': torch.tensor([0.5, 0.25], device=torch.device('cpu'))}\\n"
    "def compute_dense_reward(env, obs, action, info):\\n"
    "    return torch.zeros(1)\\n")
module = load_reward_module(folder / "reward.py", trusted=False)
print(json.dumps(module.evaluate.__wrapped__(None)["x"].tolist()))
'''


def test_untrusted_code_in_process_builds_tensors_from_data_with_a_device():
    """torch's C++ side imports torch.storage lazily through the calling frame's __import__; the first tensor built
    from Python data with a device inside guarded reward code must not hit torch's INTERNAL ASSERT (fresh process:
    the lazy import happens once per process)."""
    out = subprocess.run([sys.executable, "-c", _TENSOR_FROM_DATA], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert json.loads(out.stdout.strip().splitlines()[-1]) == [0.5, 0.25]
