"""Model backends: anthropic (through an injected httpx2 MockTransport, never the network), record/replay, registry."""

from __future__ import annotations

import base64
import io
import json
import sys
import types

import httpx2
import pytest
from PIL import Image

from gendex_envs.task_version import TaskLayout
from generator.backends.anthropic_backend import DEFAULT_MODEL, AnthropicBackend
from generator.backends.base import Backend, ImagePart, ModelRequest, ModelResponse
from generator.backends.registry import (
    BACKEND_NAMES,
    default_backend_name,
    make_backend,
)
from generator.backends.transcript import RecordingBackend, ReplayBackend
from generator.errors import BackendError, TranscriptMismatchError


@pytest.fixture(autouse=True)
def _clean_env(monkeypatch):
    """No key, model or endpoint from the developer's shell leaks into these tests."""
    for var in ("ANTHROPIC_API_KEY", "ANTHROPIC_AUTH_TOKEN", "ANTHROPIC_BASE_URL", "ANTHROPIC_CUSTOM_HEADERS",
                "GENDEX_ANTHROPIC_MODEL"):
        monkeypatch.delenv(var, raising=False)


def png(color: tuple[int, int, int], size: int = 4) -> bytes:
    buf = io.BytesIO()
    Image.new("RGB", (size, size), color).save(buf, format="PNG")
    return buf.getvalue()


LEFT = ImagePart("left_overhead", png((200, 30, 30)))
WRIST = ImagePart("wrist", png((30, 30, 200)))


def vision_request(**changes) -> ModelRequest:
    fields = {"step": "plan", "prompt": "Does the scene match the task?\nAnswer in YAML.",
              "system": "You judge scenes.", "images": (LEFT, WRIST), "temperature": 0.2, "max_tokens": 512,
              "context": {"task": "PutAppleBowl"}}
    fields.update(changes)
    return ModelRequest(**fields)


def text_request(**changes) -> ModelRequest:
    fields = {"step": "propose", "prompt": "Propose a task with: apple, bowl.",
              "context": {"objects": ["apple", "bowl"]}}
    fields.update(changes)
    return ModelRequest(**fields)


# --------------------------------------------------------------------------------------------- a fake Messages API


def ok(*texts: str, model: str = "claude-sonnet-4-6", input_tokens: int = 11, output_tokens: int = 7,
       stop_reason: str = "end_turn", extra_blocks: tuple[dict, ...] = ()) -> httpx2.Response:
    content = [*extra_blocks, *({"type": "text", "text": t} for t in texts)]
    return httpx2.Response(200, json={
        "id": "msg_test", "type": "message", "role": "assistant", "model": model, "content": content,
        "stop_reason": stop_reason, "stop_sequence": None,
        "usage": {"input_tokens": input_tokens, "output_tokens": output_tokens}})


def api_error(status: int, kind: str, message: str, headers: dict[str, str] | None = None) -> httpx2.Response:
    return httpx2.Response(status, headers=headers,
                           json={"type": "error", "error": {"type": kind, "message": message}})


def refuse(request: httpx2.Request) -> httpx2.Response:
    raise httpx2.ConnectError("connection refused", request=request)


class FakeAPI:
    """MockTransport handler: answers each call with the next scripted reply and keeps the requests."""

    def __init__(self, *replies):
        self.replies = list(replies)
        self.requests: list[httpx2.Request] = []

    def __call__(self, request: httpx2.Request) -> httpx2.Response:
        self.requests.append(request)
        if not self.replies:
            raise AssertionError(f"unexpected call {len(self.requests)} to {request.url}")
        reply = self.replies.pop(0)
        return reply(request) if callable(reply) else reply

    @property
    def bodies(self) -> list[dict]:
        return [json.loads(r.content) for r in self.requests]


def anthropic_backend(api: FakeAPI, **kw) -> tuple[AnthropicBackend, list[float]]:
    sleeps: list[float] = []
    kw.setdefault("api_key", "sk-ant-test")
    backend = AnthropicBackend(http_client=httpx2.Client(transport=httpx2.MockTransport(api)), sleep=sleeps.append,
                               **kw)
    return backend, sleeps


# ------------------------------------------------------------------------------------------------------ anthropic


def test_anthropic_sends_system_views_images_then_prompt_and_parses_text_and_usage():
    api = FakeAPI(ok("scene_ok: true\n", "reason: \"fine\"", input_tokens=1234, output_tokens=56,
                     extra_blocks=({"type": "thinking", "thinking": "hmm", "signature": "sig"},)))
    backend, sleeps = anthropic_backend(api, model="claude-test-model", timeout_s=45)
    resp = backend.complete(vision_request())

    assert len(api.requests) == 1 and sleeps == []
    http = api.requests[0]
    assert http.method == "POST" and http.url.path == "/v1/messages"
    assert http.headers["authorization"] == "Bearer sk-ant-test"
    assert http.headers["x-stainless-retry-count"] == "0"  # the SDK's own retry is off; ours counts
    assert http.headers["x-stainless-timeout"] == "45"
    body = api.bodies[0]
    assert body["model"] == "claude-test-model"
    assert body["system"] == "You judge scenes."
    assert body["max_tokens"] == 512
    # the 2.x SDK speaks API version 2026-10-21, which rejects sampling parameters: temperature is not sent
    assert "temperature" not in body and "top_p" not in body and "top_k" not in body
    assert [m["role"] for m in body["messages"]] == ["user"]
    content = body["messages"][0]["content"]
    assert [b["type"] for b in content] == ["text", "image", "text", "image", "text"]
    assert content[0] == {"type": "text", "text": "View: left_overhead"}
    assert content[1] == {"type": "image", "source": {"type": "base64", "media_type": "image/png",
                                                      "data": base64.b64encode(LEFT.png).decode()}}
    assert content[2] == {"type": "text", "text": "View: wrist"}
    assert base64.b64decode(content[3]["source"]["data"]) == WRIST.png
    assert content[4] == {"type": "text", "text": "Does the scene match the task?\nAnswer in YAML."}
    assert "context" not in json.dumps(body)  # context is for the offline backend only

    assert resp == ModelResponse(text='scene_ok: true\nreason: "fine"', backend="anthropic",
                                 model="claude-sonnet-4-6", usage={"input_tokens": 1234, "output_tokens": 56})


def test_anthropic_text_only_request_has_no_system_and_one_text_block():
    api = FakeAPI(ok("{}"))
    backend, _ = anthropic_backend(api)
    backend.complete(text_request())
    body = api.bodies[0]
    assert "system" not in body
    assert body["model"] == DEFAULT_MODEL
    assert body["messages"] == [{"role": "user", "content": [
        {"type": "text", "text": "Propose a task with: apple, bowl."}]}]


def test_anthropic_is_a_vision_language_backend():
    backend, _ = anthropic_backend(FakeAPI())
    assert isinstance(backend, Backend)
    assert (backend.name, backend.sees_images, backend.is_language_model) == ("anthropic", True, True)


def test_anthropic_model_from_argument_then_env_then_default(monkeypatch):
    assert anthropic_backend(FakeAPI())[0].model == DEFAULT_MODEL
    monkeypatch.setenv("GENDEX_ANTHROPIC_MODEL", "claude-from-env")
    assert anthropic_backend(FakeAPI())[0].model == "claude-from-env"
    assert anthropic_backend(FakeAPI(), model="claude-explicit")[0].model == "claude-explicit"


def test_anthropic_key_from_env(monkeypatch):
    monkeypatch.setenv("ANTHROPIC_API_KEY", "sk-ant-from-env")
    api = FakeAPI(ok("x"))
    backend, _ = anthropic_backend(api, api_key=None)
    backend.complete(text_request())
    assert api.requests[0].headers["authorization"] == "Bearer sk-ant-from-env"


@pytest.mark.parametrize("key", [None, "", "   "])
def test_anthropic_without_key_says_how_to_set_it(key):
    with pytest.raises(BackendError, match=r"ANTHROPIC_API_KEY.*--backend offline"):
        AnthropicBackend(api_key=key)


def test_anthropic_retries_overload_and_server_error_then_succeeds():
    api = FakeAPI(api_error(529, "overloaded_error", "Overloaded"), api_error(500, "api_error", "Internal"),
                  ok("fine"))
    backend, sleeps = anthropic_backend(api, max_retries=3, backoff_s=0.5)
    assert backend.complete(text_request()).text == "fine"
    assert len(api.requests) == 3
    assert sleeps == [0.5, 1.0]  # exponential back-off, injected sleep: no real waiting
    assert api.bodies[0] == api.bodies[2]


def test_anthropic_retries_rate_limit_honouring_retry_after():
    api = FakeAPI(api_error(429, "rate_limit_error", "slow down", headers={"retry-after": "3"}), ok("done"))
    backend, sleeps = anthropic_backend(api)
    assert backend.complete(text_request()).text == "done"
    assert len(api.requests) == 2 and sleeps == [3.0]


def test_anthropic_retries_connection_errors():
    api = FakeAPI(refuse, ok("back"))
    backend, sleeps = anthropic_backend(api, max_retries=1)
    assert backend.complete(text_request()).text == "back"
    assert len(api.requests) == 2 and len(sleeps) == 1


def test_anthropic_persistent_server_error_gives_up_after_max_retries():
    api = FakeAPI(*[api_error(500, "api_error", "Internal server error")] * 3)
    backend, sleeps = anthropic_backend(api, max_retries=2)
    with pytest.raises(BackendError) as info:
        backend.complete(text_request())
    assert len(api.requests) == 3 and len(sleeps) == 2
    msg = str(info.value)
    assert "after 3 attempt(s)" in msg and "max_retries=2" in msg and "500" in msg and "Internal server error" in msg
    assert "propose" in msg


def test_anthropic_persistent_connection_error_gives_up():
    api = FakeAPI(refuse, refuse)
    backend, _ = anthropic_backend(api, max_retries=1)
    with pytest.raises(BackendError, match=r"after 2 attempt\(s\).*APIConnectionError"):
        backend.complete(text_request())
    assert len(api.requests) == 2


def test_anthropic_unknown_model_fails_at_once_naming_it():
    api = FakeAPI(api_error(404, "not_found_error", "model: claude-nope-9"))
    backend, sleeps = anthropic_backend(api, model="claude-nope-9", max_retries=3)
    with pytest.raises(BackendError) as info:
        backend.complete(text_request())
    assert len(api.requests) == 1 and sleeps == []
    msg = str(info.value)
    assert "404" in msg and "not_found_error" in msg and "'claude-nope-9'" in msg and "model: claude-nope-9" in msg
    assert "GENDEX_ANTHROPIC_MODEL" in msg


@pytest.mark.parametrize(("status", "kind", "hint"), [
    (400, "invalid_request_error", "prompt is too long"),
    (401, "authentication_error", "ANTHROPIC_API_KEY"),
])
def test_anthropic_client_errors_fail_at_once(status, kind, hint):
    api = FakeAPI(api_error(status, kind, "prompt is too long" if status == 400 else "invalid x-api-key"))
    backend, sleeps = anthropic_backend(api)
    with pytest.raises(BackendError, match=str(status)) as info:
        backend.complete(text_request())
    assert hint in str(info.value) and kind in str(info.value)
    assert len(api.requests) == 1 and sleeps == []


def test_anthropic_rejects_non_png_images_before_calling():
    api = FakeAPI()
    backend, _ = anthropic_backend(api)
    with pytest.raises(BackendError, match="'left_overhead'.*not a PNG"):
        backend.complete(vision_request(images=(ImagePart("left_overhead", b"\xff\xd8\xff\xe0JFIF"),)))
    assert api.requests == []


def test_anthropic_reply_without_text_is_an_error():
    api = FakeAPI(ok(stop_reason="refusal"))
    backend, _ = anthropic_backend(api)
    with pytest.raises(BackendError, match="no text.*refusal"):
        backend.complete(text_request())


def test_anthropic_injected_sdk_client_is_used_without_key():
    calls = []

    class Messages:
        def create(self, **kw):
            calls.append(kw)
            block = types.SimpleNamespace(type="text", text="from fake client")
            usage = types.SimpleNamespace(input_tokens=1, output_tokens=2)
            return types.SimpleNamespace(content=[block], usage=usage, model="m", stop_reason="end_turn")

    backend = AnthropicBackend(client=types.SimpleNamespace(messages=Messages()), model="m")
    assert backend.complete(text_request()).text == "from fake client"
    assert calls[0]["model"] == "m"


# ------------------------------------------------------------------------------------------------ record / replay


class EchoBackend:
    """A deterministic stand-in backend whose answers depend on the whole request (images included)."""

    name = "echo"
    model = "echo-1"
    is_language_model = False

    def __init__(self, sees_images: bool = True):
        self.sees_images = sees_images
        self.calls = 0

    def complete(self, request: ModelRequest) -> ModelResponse:
        self.calls += 1
        text = f"{request.step} #{self.calls} {request.digest()[:12]}\n  é ✓ \"quoted\"\t\\ \r\n{request.prompt}"
        return ModelResponse(text=text, backend=self.name, model=self.model, usage={"calls": self.calls})


def record(tmp_path, requests, inner=None):
    path = TaskLayout(tmp_path / "run").transcript
    rec = RecordingBackend(inner or EchoBackend(), path)
    return path, [rec.complete(r) for r in requests]


def test_record_then_replay_is_byte_identical_with_images(tmp_path):
    requests = [text_request(), vision_request(), vision_request(step="analyze", images=(WRIST,))]
    path, recorded = record(tmp_path, requests)

    lines = path.read_text(encoding="utf-8").splitlines()
    assert len(lines) == 1 + len(requests)
    header = json.loads(lines[0])["header"]
    assert header | {} == {"format": "gendex-transcript", "version": 2, "backend": "echo", "model": "echo-1",
                           "sees_images": True, "is_language_model": False}
    second = json.loads(lines[2])
    assert (second["index"], second["step"], second["digest"]) == (1, "plan", requests[1].digest())
    assert second["request"]["images"] == [{"name": "left_overhead", "sha256": LEFT.sha256(), "bytes": len(LEFT.png)},
                                           {"name": "wrist", "sha256": WRIST.sha256(), "bytes": len(WRIST.png)}]
    assert LEFT.b64() not in path.read_text(encoding="utf-8")  # images are not stored inline

    replay = ReplayBackend(path)
    replayed = [replay.complete(r) for r in requests]
    assert replayed == recorded
    assert [r.text.encode() for r in replayed] == [r.text.encode() for r in recorded]
    assert replay.remaining == 0
    replay.assert_consumed()


def test_recording_flushes_each_exchange_as_it_goes(tmp_path):
    path = tmp_path / "t.jsonl"
    rec = RecordingBackend(EchoBackend(), path)
    assert len(path.read_text().splitlines()) == 1  # header right away
    rec.complete(text_request())
    assert len(path.read_text().splitlines()) == 2
    rec.complete(text_request(prompt="again"))
    assert len(path.read_text().splitlines()) == 3 and rec.count == 2


def test_recording_passes_the_inner_backend_through(tmp_path):
    inner = EchoBackend(sees_images=False)
    rec = RecordingBackend(inner, tmp_path / "t.jsonl")
    assert isinstance(rec, Backend)
    assert (rec.name, rec.model, rec.sees_images, rec.is_language_model) == ("record", "echo-1", False, False)
    assert rec.complete(text_request()).backend == "echo"


def test_recording_refuses_to_overwrite_unless_asked(tmp_path):
    path, _ = record(tmp_path, [text_request()])
    with pytest.raises(BackendError, match="already exists"):
        RecordingBackend(EchoBackend(), path)
    RecordingBackend(EchoBackend(), path, overwrite=True)
    assert len(path.read_text().splitlines()) == 1


def test_replay_takes_the_recorded_backend_attributes(tmp_path):
    path, _ = record(tmp_path, [text_request()], inner=EchoBackend(sees_images=False))
    replay = ReplayBackend(path)
    assert isinstance(replay, Backend)
    assert (replay.name, replay.model, replay.sees_images, replay.is_language_model) == \
        ("replay", "echo-1", False, False)
    assert replay.recorded_backend == "echo" and len(replay) == 1


def test_replay_of_changed_prompt_names_index_step_and_where(tmp_path):
    path, _ = record(tmp_path, [text_request(), text_request(prompt="line one\nline two: apple")])
    replay = ReplayBackend(path)
    replay.complete(text_request())
    with pytest.raises(TranscriptMismatchError) as info:
        replay.complete(text_request(prompt="line one\nline two: pear"))
    msg = str(info.value)
    assert "request 1 (step propose)" in msg and "prompt differs at line 2 col 11" in msg
    assert "recorded 'line two: apple'" in msg and "now 'line two: pear'" in msg


def test_replay_of_changed_image_bytes_is_a_mismatch(tmp_path):
    path, _ = record(tmp_path, [vision_request()])
    with pytest.raises(TranscriptMismatchError, match=r"request 0 \(step plan\).*image bytes of \['wrist'\]"):
        ReplayBackend(path).complete(vision_request(images=(LEFT, ImagePart("wrist", png((30, 31, 200))))))


def test_replay_of_changed_step_context_or_settings_is_a_mismatch(tmp_path):
    path, _ = record(tmp_path, [vision_request()])
    with pytest.raises(TranscriptMismatchError, match="step 'plan' -> 'analyze'"):
        ReplayBackend(path).complete(vision_request(step="analyze"))
    with pytest.raises(TranscriptMismatchError, match=r"context keys \['task'\]"):
        ReplayBackend(path).complete(vision_request(context={"task": "Other"}))
    with pytest.raises(TranscriptMismatchError, match="max_tokens 512 -> 100"):
        ReplayBackend(path).complete(vision_request(max_tokens=100))
    with pytest.raises(TranscriptMismatchError, match=r"image names \['left_overhead', 'wrist'\] -> \['wrist'\]"):
        ReplayBackend(path).complete(vision_request(images=(WRIST,)))


def test_replay_past_the_end_is_a_mismatch(tmp_path):
    path, _ = record(tmp_path, [text_request()])
    replay = ReplayBackend(path)
    replay.complete(text_request())
    with pytest.raises(TranscriptMismatchError, match=r"request 1 \(step plan\) is past the end.*holds 1"):
        replay.complete(vision_request())


def test_replay_not_consumed_is_reported(tmp_path):
    path, _ = record(tmp_path, [text_request(), vision_request()])
    replay = ReplayBackend(path)
    replay.complete(text_request())
    with pytest.raises(TranscriptMismatchError, match=r"made 1 request\(s\) but 2 were recorded.*step plan"):
        replay.assert_consumed()


def test_recorded_backend_errors_replay_as_the_same_error(tmp_path):
    class Flaky(EchoBackend):
        def complete(self, request):
            if self.calls == 0:
                self.calls += 1
                raise BackendError("Anthropic API answered 500 after 4 attempt(s)")
            return super().complete(request)

    path = tmp_path / "t.jsonl"
    rec = RecordingBackend(Flaky(), path)
    with pytest.raises(BackendError):
        rec.complete(text_request())
    ok_resp = rec.complete(text_request())

    replay = ReplayBackend(path)
    with pytest.raises(BackendError, match="replayed.*500 after 4"):
        replay.complete(text_request())
    assert replay.complete(text_request()) == ok_resp


def test_replay_missing_transcript(tmp_path):
    with pytest.raises(BackendError, match="nope.jsonl not found"):
        ReplayBackend(tmp_path / "nope.jsonl")


@pytest.mark.parametrize(("mangle", "line", "what"), [
    (lambda lines: lines[:1] + ['{"index": 0, "step": "propose", "dig'], 2, "not valid JSON"),
    (lambda lines: lines[1:], 1, "first line must be the header"),
    (lambda lines: [], 1, "empty"),
    (lambda lines: lines[:1] + lines[2:], 2, "index 1, expected 0"),
    (lambda lines: lines + [lines[0]], 4, "second header"),
    (lambda lines: lines[:2] + [lines[2].replace('"text": ', '"txt": ')], 3, "'text' must be a string"),
    (lambda lines: [lines[0].replace('"sees_images": true', '"sees_images": "yes"')] + lines[1:], 1, "sees_images"),
])
def test_replay_corrupt_transcript_names_path_and_line(tmp_path, mangle, line, what):
    path, _ = record(tmp_path, [text_request(), vision_request()])
    lines = path.read_text(encoding="utf-8").splitlines()
    path.write_text("\n".join(mangle(lines)) + "\n", encoding="utf-8")
    with pytest.raises(TranscriptMismatchError) as info:
        ReplayBackend(path)
    assert f"{path}:{line}:" in str(info.value) and what in str(info.value)


def test_record_and_replay_through_the_anthropic_backend(tmp_path):
    api = FakeAPI(ok("propose: apple\n"), ok("scene_ok: ", "false  \n"))
    live, _ = anthropic_backend(api)
    path = tmp_path / "claude.jsonl"
    rec = RecordingBackend(live, path)
    requests = [text_request(), vision_request()]
    recorded = [rec.complete(r) for r in requests]
    assert [r.text for r in recorded] == ["propose: apple\n", "scene_ok: false  \n"]

    replay = ReplayBackend(path)
    assert (replay.model, replay.sees_images, replay.is_language_model) == (DEFAULT_MODEL, True, True)
    assert [replay.complete(r) for r in requests] == recorded
    assert len(api.requests) == 2  # the replay made no HTTP call


# ------------------------------------------------------------------------------------------------------- registry


def test_make_backend_unknown_name_lists_the_allowed_ones():
    with pytest.raises(BackendError, match="unknown backend 'gpt'.*anthropic, offline, replay"):
        make_backend("gpt")
    assert BACKEND_NAMES == ("anthropic", "offline", "replay")


def test_make_backend_replay_needs_a_transcript(tmp_path):
    with pytest.raises(BackendError, match="needs a transcript"):
        make_backend("replay")
    path, _ = record(tmp_path, [text_request()])
    replay = make_backend("replay", transcript=path)
    assert isinstance(replay, ReplayBackend) and replay.model == "echo-1"


def test_make_backend_anthropic(tmp_path):
    with pytest.raises(BackendError, match="ANTHROPIC_API_KEY"):
        make_backend("anthropic")
    api = FakeAPI(ok("hi"))
    client = httpx2.Client(transport=httpx2.MockTransport(api))
    backend = make_backend("Anthropic", model="claude-x", api_key="k", http_client=client)
    assert isinstance(backend, AnthropicBackend) and backend.model == "claude-x"

    recorded = make_backend("anthropic", api_key="k", http_client=client, transcript=tmp_path / "t.jsonl")
    assert isinstance(recorded, RecordingBackend) and isinstance(recorded.inner, AnthropicBackend)
    assert recorded.complete(text_request()).text == "hi"
    with pytest.raises(BackendError, match="already exists"):
        make_backend("anthropic", api_key="k", http_client=client, transcript=tmp_path / "t.jsonl")
    make_backend("anthropic", api_key="k", http_client=client, transcript=tmp_path / "t.jsonl",
                 overwrite_transcript=True)


def test_make_backend_offline_missing_module(monkeypatch):
    monkeypatch.setitem(sys.modules, "generator.backends.offline", None)  # import fails as if the file were absent
    with pytest.raises(BackendError, match="offline backend is not available"):
        make_backend("offline")


def test_make_backend_offline_gets_the_seed(monkeypatch, tmp_path):
    class OfflineBackend(EchoBackend):
        name = "offline"

        def __init__(self, seed=0):
            super().__init__(sees_images=False)
            self.seed = seed

    fake = types.ModuleType("generator.backends.offline")
    fake.OfflineBackend = OfflineBackend
    monkeypatch.setitem(sys.modules, "generator.backends.offline", fake)
    assert make_backend("offline", seed=7).seed == 7
    recorded = make_backend("offline", seed=3, transcript=tmp_path / "off.jsonl")
    assert isinstance(recorded, RecordingBackend) and recorded.inner.seed == 3


def test_default_backend_name(monkeypatch):
    assert default_backend_name() == "offline"
    monkeypatch.setenv("ANTHROPIC_API_KEY", " ")
    assert default_backend_name() == "offline"
    monkeypatch.setenv("ANTHROPIC_API_KEY", "sk-ant-x")
    assert default_backend_name() == "anthropic"


def test_a_format_1_transcript_is_refused_with_its_reason(task_version):
    """Transcripts recorded before the pipeline's requests named their step document a task but do not replay."""
    files = task_version("LiftApple", 0).files
    committed = files.resolve(files.transcript)
    with pytest.raises(TranscriptMismatchError, match=r"unsupported transcript format 'gendex-transcript' version 1; "
                                                      r"this reader knows 'gendex-transcript' version 2"):
        ReplayBackend(committed)
