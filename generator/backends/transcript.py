"""The ``record`` and ``replay`` backends: save every exchange of a run as JSONL, and serve it back byte for byte.

A transcript is one JSON object per line, appended and flushed exchange by exchange (a crashed run keeps what it
got). The first line is a header describing the recorded backend, so a replay takes the same pipeline branches::

    {"header": {"format": "gendex-transcript", "version": 2, "backend": "anthropic", "model": "...",
                "sees_images": true, "is_language_model": true}}
    {"index": 0, "step": "propose", "digest": "<ModelRequest.digest()>",
     "request": {"step", "system", "prompt", "temperature", "max_tokens", "context",
                 "images": [{"name", "sha256", "bytes"}]},
     "response": {"text", "backend", "model", "usage"}}

Images are stored by SHA-256, not inline; the digest covers them. An exchange whose backend raised
:class:`~generator.errors.BackendError` is stored with ``"error": {"type", "message"}`` instead of ``"response"``, and
replays as the same error, so a pipeline that retried after a failed call makes the same calls on replay.

Replay is strict: the request at position ``i`` must have the digest recorded at ``i``, else
:class:`~generator.errors.TranscriptMismatchError` names the index, the step and which fields differ.
"""

from __future__ import annotations

import json
import logging
import threading
from pathlib import Path
from typing import Any

from gendex_envs.typed_yaml import (
    MAX_INPUT_BYTES,
    MAX_TRANSCRIPT_BYTES,
    MAX_TRANSCRIPT_EXCHANGES,
    MAX_TRANSCRIPT_LINE_BYTES,
    parse_json_bounded,
)
from generator.backends.base import Backend, ModelRequest, ModelResponse
from generator.errors import BackendError, TranscriptMismatchError

log = logging.getLogger(__name__)

FORMAT = "gendex-transcript"
VERSION = 2
"""Transcript format; 2 names the asking pipeline step ``step`` (1 said ``stage``), so version 1 transcripts,
recorded by an older generator with other prompts, document how a task was made but do not replay."""
_HINT_CHARS = 40


class RecordingBackend:
    """Wraps ``inner`` and appends every exchange to the JSONL transcript at ``path``.

    Behaves like ``inner`` (same ``model``, ``sees_images``, ``is_language_model``; responses pass through
    unchanged). The header is written at construction. An existing non-empty ``path`` is refused unless
    ``overwrite=True``: a recorded run can be costly to redo.
    """

    name = "record"

    def __init__(self, inner: Backend, path: str | Path, *, overwrite: bool = False) -> None:
        self.inner = inner
        self.path = Path(path)
        self.model = inner.model
        self.sees_images = inner.sees_images
        self.is_language_model = inner.is_language_model
        self._count = 0
        self._lock = threading.Lock()
        if self.path.exists() and self.path.stat().st_size > 0 and not overwrite:
            raise BackendError(f"transcript {self.path} already exists; remove it, record to another path, "
                               "or pass overwrite=True")
        header = {"format": FORMAT, "version": VERSION,
                  "backend": getattr(inner, "recorded_backend", inner.name),  # recording a replay: the original's
                  "model": inner.model,
                  "sees_images": bool(inner.sees_images), "is_language_model": bool(inner.is_language_model)}
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self.path.write_text(_dumps({"header": header}) + "\n", encoding="utf-8")
        except OSError as err:
            raise BackendError(f"cannot write transcript {self.path}: {err}") from err
        log.info("recording %s exchanges to %s", inner.name, self.path)

    def __repr__(self) -> str:
        return f"RecordingBackend({self.inner!r}, {str(self.path)!r})"

    @property
    def count(self) -> int:
        """Exchanges written so far."""
        return self._count

    def complete(self, request: ModelRequest) -> ModelResponse:
        try:
            response = self.inner.complete(request)
        except BackendError as err:
            self._append(request, {"error": {"type": type(err).__name__, "message": str(err)}})
            raise
        self._append(request, {"response": response.to_record()})
        return response

    def _append(self, request: ModelRequest, outcome: dict[str, Any]) -> None:
        with self._lock:
            line = {"index": self._count, "step": request.step, "digest": request.digest(),
                    "request": request.to_record(), **outcome}
            try:
                with self.path.open("a", encoding="utf-8") as fh:
                    fh.write(_dumps(line) + "\n")
                    fh.flush()
            except OSError as err:
                raise BackendError(f"cannot append exchange {self._count} to transcript {self.path}: {err}") from err
            self._count += 1


class ReplayBackend:
    """Serves the exchanges of a recorded transcript back, in order, checking each request's digest.

    ``model``, ``sees_images`` and ``is_language_model`` are the recorded backend's (from the header); responses are
    returned exactly as recorded (their ``backend`` field names the recorded backend).
    """

    name = "replay"

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.header, self._exchanges = _load(self.path)
        self.model: str = self.header["model"]
        self.sees_images: bool = self.header["sees_images"]
        self.is_language_model: bool = self.header["is_language_model"]
        self.recorded_backend: str = self.header["backend"]
        self._next = 0
        self._lock = threading.Lock()
        log.info("replaying %d exchange(s) of a %s run (model %s) from %s", len(self._exchanges),
                 self.recorded_backend, self.model, self.path)

    def __repr__(self) -> str:
        return f"ReplayBackend({str(self.path)!r})"

    def __len__(self) -> int:
        return len(self._exchanges)

    @property
    def remaining(self) -> int:
        """Exchanges not served yet."""
        return len(self._exchanges) - self._next

    def complete(self, request: ModelRequest) -> ModelResponse:
        with self._lock:
            index = self._next
            if index >= len(self._exchanges):
                raise TranscriptMismatchError(
                    f"replay of {self.path}: request {index} (step {request.step}) is past the end of the "
                    f"transcript, which holds {len(self._exchanges)} exchange(s); the run asks for more than was "
                    "recorded")
            exchange = self._exchanges[index]
            digest = request.digest()
            if digest != exchange["digest"]:
                raise TranscriptMismatchError(
                    f"replay of {self.path}: request {index} (step {request.step}) differs from the recorded one "
                    f"(step {exchange['step']}, line {exchange['line']}): {_differences(exchange, request)}")
            self._next += 1
        if "error" in exchange:
            err = exchange["error"]
            raise BackendError(f"(replayed from {self.path}, exchange {index}) {err.get('message', '')}")
        return exchange["response"]

    def assert_consumed(self) -> None:
        """Raise :class:`TranscriptMismatchError` when the run ended before using every recorded exchange."""
        if self.remaining:
            nxt = self._exchanges[self._next]
            raise TranscriptMismatchError(
                f"replay of {self.path}: the run made {self._next} request(s) but {len(self._exchanges)} were "
                f"recorded; the next unused one is exchange {self._next} (step {nxt['step']}, line {nxt['line']})")


def _dumps(obj: Any) -> str:
    return json.dumps(obj, ensure_ascii=False, default=str)


def _load(path: Path) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """Parse and check a transcript; returns the header and the exchanges (responses already parsed).

    A transcript is untrusted (it may come with a shared task folder): the file, each line, the number of exchanges
    and each replayed reply are bounded (``MAX_TRANSCRIPT_*``, ``MAX_INPUT_BYTES``) and each line is parsed with the
    depth and node bounds of :func:`~gendex_envs.typed_yaml.parse_json_bounded`."""
    try:
        with path.open("rb") as fh:
            data = fh.read(MAX_TRANSCRIPT_BYTES + 1)
    except FileNotFoundError as err:
        raise BackendError(f"transcript {path} not found (record one with a live backend and a transcript path)"
                           ) from err
    except OSError as err:
        raise BackendError(f"cannot read transcript {path}: {err}") from err
    if len(data) > MAX_TRANSCRIPT_BYTES:
        raise TranscriptMismatchError(f"transcript {path} is larger than {MAX_TRANSCRIPT_BYTES} bytes; at most "
                                      f"{MAX_TRANSCRIPT_BYTES} are allowed (MAX_TRANSCRIPT_BYTES)")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise BackendError(f"cannot read transcript {path}: not UTF-8 text (byte at offset {err.start})") from None
    header: dict[str, Any] | None = None
    exchanges: list[dict[str, Any]] = []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        if not raw.strip():
            continue
        where = f"{path}:{lineno}"
        if len(exchanges) >= MAX_TRANSCRIPT_EXCHANGES:
            raise TranscriptMismatchError(f"{where}: more than {MAX_TRANSCRIPT_EXCHANGES} exchanges; at most "
                                          f"{MAX_TRANSCRIPT_EXCHANGES} are allowed (MAX_TRANSCRIPT_EXCHANGES)")
        try:
            obj = parse_json_bounded(raw, f"line {lineno}", max_bytes=MAX_TRANSCRIPT_LINE_BYTES, max_string=None,
                                     finite=False)  # json.dumps writes NaN; a recorded context may hold one
        except json.JSONDecodeError as err:
            raise TranscriptMismatchError(f"{where}: not valid JSON ({err.msg} at column {err.colno}); "
                                          "the transcript is corrupt or truncated") from err
        except ValueError as err:  # InputBoundsError: too long, too deep, too many nodes, duplicate keys
            raise TranscriptMismatchError(f"{where}: refused: {getattr(err, 'problem', None) or err}") from None
        if not isinstance(obj, dict):
            raise TranscriptMismatchError(f"{where}: expected a JSON object, got {type(obj).__name__}")
        if header is None:
            header = _check_header(obj, where)
            continue
        exchanges.append(_check_exchange(obj, where, lineno, expected_index=len(exchanges)))
    if header is None:
        raise TranscriptMismatchError(f"{path}:1: transcript is empty (no header line)")
    return header, exchanges


def _check_header(obj: dict[str, Any], where: str) -> dict[str, Any]:
    header = obj.get("header")
    if not isinstance(header, dict):
        raise TranscriptMismatchError(f"{where}: the first line must be the header object {{\"header\": {{...}}}}")
    if header.get("format", FORMAT) != FORMAT or header.get("version", VERSION) != VERSION:
        raise TranscriptMismatchError(f"{where}: unsupported transcript format {header.get('format')!r} version "
                                      f"{header.get('version')!r}; this reader knows {FORMAT!r} version {VERSION}")
    for key, kind in (("backend", str), ("model", str), ("sees_images", bool), ("is_language_model", bool)):
        if not isinstance(header.get(key), kind):
            raise TranscriptMismatchError(f"{where}: header field {key!r} must be a {kind.__name__}, "
                                          f"got {header.get(key)!r}")
    return header


def _check_exchange(obj: dict[str, Any], where: str, lineno: int, expected_index: int) -> dict[str, Any]:
    if "header" in obj:
        raise TranscriptMismatchError(f"{where}: a second header; transcripts hold one run each")
    if obj.get("index") != expected_index:
        raise TranscriptMismatchError(f"{where}: exchange index {obj.get('index')!r}, expected {expected_index} "
                                      "(lines missing or reordered)")
    for key in ("step", "digest"):
        if not isinstance(obj.get(key), str):
            raise TranscriptMismatchError(f"{where}: field {key!r} must be a string, got {obj.get(key)!r:.80}")
    if not isinstance(obj.get("request"), dict):
        raise TranscriptMismatchError(f"{where}: field 'request' must be an object")
    out = {"index": expected_index, "line": lineno, "step": obj["step"], "digest": obj["digest"],
           "request": obj["request"]}
    if "error" in obj:
        if not isinstance(obj["error"], dict):
            raise TranscriptMismatchError(f"{where}: field 'error' must be an object")
        out["error"] = obj["error"]
        return out
    try:
        out["response"] = ModelResponse.from_record(obj.get("response"))
    except TypeError as err:
        raise TranscriptMismatchError(f"{where}: {err}") from err
    text = out["response"].text
    if isinstance(text, str) and len(text.encode("utf-8", "surrogatepass")) > MAX_INPUT_BYTES:
        raise TranscriptMismatchError(f"{where}: the recorded reply is {len(text.encode('utf-8', 'surrogatepass'))} "
                                      f"bytes; at most {MAX_INPUT_BYTES} are allowed (MAX_INPUT_BYTES)")
    return out


def _differences(exchange: dict[str, Any], request: ModelRequest) -> str:
    """Which request fields differ from the recorded ones, with a short hint for text fields."""
    old, new = exchange["request"], request.to_record()
    parts: list[str] = []
    for key in ("step", "temperature", "max_tokens"):
        if old.get(key) != new[key]:
            parts.append(f"{key} {old.get(key)!r} -> {new[key]!r}")
    for key in ("system", "prompt"):
        if old.get(key) != new[key]:
            parts.append(f"{key} {_text_hint(str(old.get(key, '')), new[key])}")
    if old.get("context") != new["context"]:
        oc, nc = old.get("context") or {}, new["context"]
        if isinstance(oc, dict):
            keys = sorted(k for k in set(oc) | set(nc) if oc.get(k) != nc.get(k))
            parts.append(f"context keys {keys}")
        else:
            parts.append("context")
    old_images = [(i.get("name"), i.get("sha256")) for i in old.get("images", []) if isinstance(i, dict)]
    new_images = [(i["name"], i["sha256"]) for i in new["images"]]
    if old_images != new_images:
        if [n for n, _ in old_images] != [n for n, _ in new_images]:
            parts.append(f"image names {[n for n, _ in old_images]} -> {[n for n, _ in new_images]}")
        else:
            changed = [n for (n, a), (_, b) in zip(old_images, new_images, strict=True) if a != b]
            parts.append(f"image bytes of {changed}")
    return "; ".join(parts) or "the digest differs but no recorded field does (recorded by another digest version?)"


def _text_hint(old: str, new: str) -> str:
    """Where two strings first differ, as ``line L col C: recorded '…' vs now '…'``."""
    i = next((k for k, (a, b) in enumerate(zip(old, new, strict=False)) if a != b), min(len(old), len(new)))
    line = old.count("\n", 0, i) + 1
    col = i - (old.rfind("\n", 0, i) + 1) + 1
    lo = max(0, i - 10)
    return (f"differs at line {line} col {col} (lengths {len(old)} vs {len(new)}): "
            f"recorded {old[lo:i + _HINT_CHARS]!r} vs now {new[lo:i + _HINT_CHARS]!r}")
