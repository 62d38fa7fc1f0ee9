"""Read a reward module's text exactly once, strictly as UTF-8, so that what is checked is what runs.

Python's importer decodes a file by its BOM and its ``coding:`` declaration (PEP 263) and prefers a cached
``__pycache__/*.pyc`` over the source; the static check reads text. Any difference between the two readings is
code that runs unchecked: a ``# -*- coding: utf-7 -*-`` line turns what the checker reads as a comment into
statements, and an unchecked-hash ``.pyc`` shipped in the folder runs instead of the source. So reward modules are
never imported from their path: :func:`read_reward_source` reads the bytes once (bounded), refuses anything that
is not plain UTF-8, and :func:`compile_reward_source` compiles that same text; the caller executes the code object
(:func:`gendex_envs.reward_module.load_reward_module`). No ``__pycache__`` is read or written, and no other file of
the folder (extra ``.py``, ``.pyc``, ``.so``) is ever looked at.
"""

from __future__ import annotations

import codecs
import re
from pathlib import Path
from types import CodeType

from gendex_envs.code_check.rules import MAX_SOURCE_BYTES
from gendex_envs.errors import RewardCodeError, UnsafeCodeError

_OTHER_BOMS = (  # UTF-32 first: its little-endian BOM starts with UTF-16's
    (codecs.BOM_UTF32_LE, "UTF-32-LE"), (codecs.BOM_UTF32_BE, "UTF-32-BE"),
    (codecs.BOM_UTF16_LE, "UTF-16-LE"), (codecs.BOM_UTF16_BE, "UTF-16-BE"),
)
_COOKIE = re.compile(r"^[ \t\f]*#.*?coding[:=][ \t]*([-\w.]+)", re.ASCII)
"""PEP 263's declaration, as the importer matches it on line 1 or 2 (checked on both, whatever line 1 holds)."""
_UTF8 = frozenset({"utf-8", "utf-8-sig"})
_ONLY = "only UTF-8 is allowed (optionally with a UTF-8 byte-order mark): what runs must be exactly the text checked"


def decode_reward_source(data: bytes, filename: str) -> str:
    """The text of a reward module's bytes; raises :class:`UnsafeCodeError` for a non-UTF-8 BOM, a ``coding:``
    declaration naming another encoding, or bytes that are not valid UTF-8, and :class:`RewardCodeError` when the
    file is larger than :data:`~gendex_envs.code_check.rules.MAX_SOURCE_BYTES`."""
    if len(data) > MAX_SOURCE_BYTES:
        raise RewardCodeError(f"{filename}: more than {MAX_SOURCE_BYTES} bytes is too long for a reward module; keep "
                              "it to the reward functions")
    for bom, name in _OTHER_BOMS:
        if data.startswith(bom):
            raise UnsafeCodeError(f"{filename}: the file starts with a {name} byte-order mark; {_ONLY}")
    bom = data.startswith(codecs.BOM_UTF8)
    if bom:
        data = data[len(codecs.BOM_UTF8):]
    try:
        text = data.decode("utf-8", errors="strict")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise UnsafeCodeError(f"{filename}: line {line}: byte {exc.start} ({data[exc.start:exc.start + 1]!r}) is not "
                              f"valid UTF-8 ({exc.reason}); {_ONLY}") from None
    # the first two lines as the importer may cut them: at "\n" (the tokenizer), at "\r" too, and as str.splitlines
    # cuts them (which also breaks at \v, \f, \x1c-\x1e: a cookie hidden behind one of those is still a cookie)
    cuts = (text.split("\n")[:2], re.split(r"\r\n|\r|\n", text)[:2], text.splitlines()[:2])
    for number, line in ((n, line) for lines in cuts for n, line in enumerate(lines, start=1)):
        match = _COOKIE.match(line)
        if match is None:
            continue
        declared = match.group(1)
        try:
            codec = codecs.lookup(declared).name
        except LookupError:
            codec = None
        spelled = declared[:12].lower().replace("_", "-")
        if codec not in _UTF8 or (bom and spelled != "utf-8" and not spelled.startswith("utf-8-")):
            # (after a BOM the importer itself accepts only `utf-8` spelled so)
            raise UnsafeCodeError(f"{filename}: line {number}: the encoding declaration `coding: {declared[:40]}` is "
                                  f"not allowed{' after a UTF-8 byte-order mark' if bom else ''}; {_ONLY}")
    return text


def read_reward_bytes(path: str | Path) -> bytes:
    """The bytes of ``path``, read once (at most :data:`~gendex_envs.code_check.rules.MAX_SOURCE_BYTES` + 1)."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"reward module {path} does not exist")
    with path.open("rb") as f:
        return f.read(MAX_SOURCE_BYTES + 1)


def read_reward_source(path: str | Path, filename: str | None = None) -> str:
    """Read ``path`` once (:func:`read_reward_bytes`) and decode it with :func:`decode_reward_source`."""
    return decode_reward_source(read_reward_bytes(path), filename or Path(path).name)


def compile_reward_source(text: str, path: str | Path) -> CodeType:
    """``text`` compiled as a module whose code objects name ``path`` (the runtime guard judges frames by their
    file name). Compiling a ``str`` ignores any ``coding:`` declaration, and nothing of this process's
    ``from __future__`` flags leaks in. Raises :class:`RewardCodeError` when it does not compile."""
    try:
        return compile(text, str(path), "exec", dont_inherit=True)
    except (SyntaxError, ValueError, RecursionError, MemoryError) as exc:
        raise RewardCodeError(f"{path}: does not compile: {type(exc).__name__}: {exc}") from None
