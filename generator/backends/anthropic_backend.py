"""The ``anthropic`` backend: Claude through the official SDK (``anthropic`` 2.x, which is built on ``httpx2``).

One :class:`~generator.backends.base.ModelRequest` becomes one ``messages.create`` call: the ``system`` prompt, and a
single user message holding, for each image, a short ``View: <name>`` text block followed by the base64 PNG block,
then the prompt text. The answer is the concatenation of the text blocks of the reply.

Sampling temperature is not sent. The 2.x SDK no longer has ``temperature`` / ``top_p`` / ``top_k`` on
``messages.create`` and sends ``anthropic-version: 2026-10-21``, under which the API answers 400 to any of them
(even 1.0). ``ModelRequest.temperature`` still takes part in the request digest and transcripts.

Retries are this module's own loop, not the SDK's (the client is built with ``max_retries=0``): 429, 5xx (529
"overloaded" included) and connection errors / time-outs are retried up to ``max_retries`` times with exponential
back-off (``retry-after`` honoured, capped); any other 4xx (bad request, bad key, unknown model id) fails at once.
The sleep is injectable so tests do not wait, and the number of HTTP calls is exactly ``max_retries + 1`` at most.
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable
from typing import Any

import anthropic
import httpx2

from generator.backends.base import ModelRequest, ModelResponse
from generator.errors import BackendError

log = logging.getLogger(__name__)

DEFAULT_MODEL = "claude-sonnet-4-6"
"""Model used when neither the ``model`` argument nor ``$GENDEX_ANTHROPIC_MODEL`` names one (vision-capable)."""
MODEL_ENV = "GENDEX_ANTHROPIC_MODEL"
API_KEY_ENV = "ANTHROPIC_API_KEY"

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
MAX_RETRY_AFTER_S = 60.0
"""Longest ``retry-after`` the backend will wait for; a longer one is cut to this."""


def resolve_model(model: str | None = None) -> str:
    """The model id to use: the argument, else ``$GENDEX_ANTHROPIC_MODEL``, else :data:`DEFAULT_MODEL`."""
    if model:
        return model
    return os.environ.get(MODEL_ENV, "").strip() or DEFAULT_MODEL


def build_content(request: ModelRequest) -> list[dict[str, Any]]:
    """The user message's content blocks: per image ``View: <name>`` then the image, then the prompt text."""
    blocks: list[dict[str, Any]] = []
    for im in request.images:
        if not im.png.startswith(PNG_MAGIC):
            raise BackendError(f"image {im.name!r} of the {request.step} request is not a PNG "
                               f"(starts with {im.png[:8]!r}); the anthropic backend sends images as image/png")
        blocks.append({"type": "text", "text": f"View: {im.name}"})
        blocks.append({"type": "image", "source": {"type": "base64", "media_type": "image/png", "data": im.b64()}})
    blocks.append({"type": "text", "text": request.prompt})
    return blocks


class AnthropicBackend:
    """Claude through the ``anthropic`` SDK; see the module docstring for what is sent and how failures are handled.

    ``http_client`` (an ``httpx2.Client``) is handed to the SDK; tests pass one with an ``httpx2.MockTransport``.
    ``client`` replaces the SDK client altogether (an ``anthropic.Anthropic``, re-configured to ``max_retries=0``, or
    any object with ``messages.create``); then no API key is needed here. ``sleep`` and ``backoff_s`` set the wait
    between attempts: ``min(backoff_s * 2**attempt, max_backoff_s)``, or the server's ``retry-after``.
    """

    name = "anthropic"
    sees_images = True
    is_language_model = True

    def __init__(self, model: str | None = None, api_key: str | None = None, max_retries: int = 3,
                 timeout_s: float = 120, http_client: httpx2.Client | None = None, client: Any = None, *,
                 sleep: Callable[[float], None] = time.sleep, backoff_s: float = 1.0,
                 max_backoff_s: float = 30.0) -> None:
        if max_retries < 0:
            raise ValueError(f"max_retries must be >= 0, got {max_retries}")
        self.model = resolve_model(model)
        self.max_retries = max_retries
        self.timeout_s = timeout_s
        self._sleep = sleep
        self._backoff_s = backoff_s
        self._max_backoff_s = max_backoff_s
        if client is not None:
            if isinstance(client, anthropic.Anthropic):
                client = client.with_options(max_retries=0)
            self._client = client
            return
        key = api_key if api_key is not None else os.environ.get(API_KEY_ENV, "")
        if not key.strip():
            raise BackendError(
                f"the anthropic backend needs an API key: set {API_KEY_ENV} (export {API_KEY_ENV}=sk-ant-...) or pass "
                "api_key=...; to generate without a model, use --backend offline")
        self._client = anthropic.Anthropic(api_key=key.strip(), max_retries=0, timeout=timeout_s,
                                           http_client=http_client)

    def __repr__(self) -> str:
        return f"AnthropicBackend(model={self.model!r}, max_retries={self.max_retries})"

    def complete(self, request: ModelRequest) -> ModelResponse:
        kwargs: dict[str, Any] = {
            "model": self.model,
            "max_tokens": request.max_tokens,
            "messages": [{"role": "user", "content": build_content(request)}],
            "timeout": self.timeout_s,
        }
        if request.system:
            kwargs["system"] = request.system
        attempts = self.max_retries + 1
        for attempt in range(attempts):
            t0 = time.monotonic()
            try:
                message = self._client.messages.create(**kwargs)
            except anthropic.APIStatusError as err:
                if not _retryable_status(err.status_code):
                    raise BackendError(self._status_message(err, request)) from err
                last: anthropic.AnthropicError = err
                wait = _retry_after(err.response)
            except anthropic.APIConnectionError as err:  # includes APITimeoutError
                last, wait = err, None
            except anthropic.AnthropicError as err:
                raise BackendError(f"anthropic backend, step {request.step}, model {self.model!r}: "
                                   f"{type(err).__name__}: {err}") from err
            else:
                return self._response(message, request, time.monotonic() - t0)
            if attempt + 1 >= attempts:
                raise BackendError(
                    f"anthropic backend: the {request.step} request to model {self.model!r} failed after {attempts} "
                    f"attempt(s) (max_retries={self.max_retries}); last error: {_describe(last)}") from last
            if wait is None:
                wait = min(self._backoff_s * 2.0 ** attempt, self._max_backoff_s)
            log.warning("anthropic %s request (model %s) failed: %s; retry %d/%d in %.1f s", request.step,
                        self.model, _describe(last), attempt + 1, self.max_retries, wait)
            self._sleep(wait)
        raise AssertionError("unreachable")  # pragma: no cover

    def _status_message(self, err: anthropic.APIStatusError, request: ModelRequest) -> str:
        what = err.api_message or str(err)
        msg = (f"Anthropic API answered {err.status_code} ({err.type or 'error'}) to the {request.step} request "
               f"for model {self.model!r}: {what}")
        if err.status_code == 401:
            msg += f"; check {API_KEY_ENV} (or use --backend offline)"
        elif err.status_code == 404:
            msg += f"; is {self.model!r} a valid model id? Pick another with --model or ${MODEL_ENV}"
        return msg

    def _response(self, message: Any, request: ModelRequest, elapsed_s: float) -> ModelResponse:
        content = getattr(message, "content", None) or []
        texts = [block.text for block in content if getattr(block, "type", None) == "text"]
        stop = getattr(message, "stop_reason", None)
        if not texts:
            raise BackendError(f"anthropic backend: the {request.step} reply of model {self.model!r} holds no text "
                               f"(stop_reason={stop!r}, blocks={[getattr(b, 'type', '?') for b in content]})")
        if stop == "max_tokens":
            log.warning("anthropic %s reply was cut at max_tokens=%d; the answer may be incomplete", request.step,
                        request.max_tokens)
        usage: dict[str, int] = {}
        raw_usage = getattr(message, "usage", None)
        for field in ("input_tokens", "output_tokens", "cache_creation_input_tokens", "cache_read_input_tokens"):
            value = getattr(raw_usage, field, None)
            if isinstance(value, int):
                usage[field] = value
        model = getattr(message, "model", None) or self.model
        log.info("anthropic %s: model %s, %d image(s), %s in / %s out tokens, %.1f s", request.step, model,
                 len(request.images), usage.get("input_tokens", "?"), usage.get("output_tokens", "?"), elapsed_s)
        return ModelResponse(text="".join(texts), backend=self.name, model=model, usage=usage)


def _retryable_status(status: int) -> bool:
    return status == 429 or status >= 500


def _retry_after(response: httpx2.Response | None) -> float | None:
    """Seconds from a ``retry-after`` header (number form only), capped at :data:`MAX_RETRY_AFTER_S`."""
    if response is None:
        return None
    raw = response.headers.get("retry-after")
    try:
        seconds = float(raw) if raw is not None else None
    except ValueError:
        return None
    if seconds is None or seconds < 0:
        return None
    return min(seconds, MAX_RETRY_AFTER_S)


def _describe(err: BaseException) -> str:
    if isinstance(err, anthropic.APIStatusError):
        return f"HTTP {err.status_code} ({err.type or 'error'}): {err.api_message or err}"
    return f"{type(err).__name__}: {err}"
