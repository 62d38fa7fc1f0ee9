"""Pick a backend by name: ``anthropic``, ``offline`` or ``replay``; any but ``replay`` can also record.

Backend modules are imported on demand (the SDK takes a while to import, and ``offline`` must work without it).
"""

from __future__ import annotations

import importlib
import logging
import os
from pathlib import Path
from typing import Any

from generator.backends.base import Backend
from generator.errors import BackendError

log = logging.getLogger(__name__)

BACKEND_NAMES = ("anthropic", "offline", "replay")
"""Names :func:`make_backend` accepts. Recording is not a name of its own: pass ``transcript=`` to a live backend."""

_OFFLINE_MODULE = "generator.backends.offline"


def default_backend_name() -> str:
    """``"anthropic"`` when ``$ANTHROPIC_API_KEY`` is set (non-empty), else ``"offline"``."""
    return "anthropic" if os.environ.get("ANTHROPIC_API_KEY", "").strip() else "offline"


def make_backend(name: str, *, seed: int = 0, model: str | None = None, transcript: str | Path | None = None,
                 overwrite_transcript: bool = False, **kw: Any) -> Backend:
    """Build the backend called ``name``.

    - ``anthropic``: :class:`~generator.backends.anthropic_backend.AnthropicBackend` (``model``, then
      ``$GENDEX_ANTHROPIC_MODEL``, then its default); ``kw`` go to its constructor (``api_key``, ``max_retries``,
      ``timeout_s``, ``http_client``, ``client``, ...). ``seed`` is not used.
    - ``offline``: ``generator.backends.offline.OfflineBackend(seed=seed, **kw)``.
    - ``replay``: :class:`~generator.backends.transcript.ReplayBackend` serving ``transcript`` (required).

    For ``anthropic`` and ``offline``, a ``transcript`` path wraps the backend in a
    :class:`~generator.backends.transcript.RecordingBackend` writing there (an existing file is refused unless
    ``overwrite_transcript``). Unknown names and missing arguments raise :class:`BackendError`.
    """
    key = name.strip().lower()
    if key not in BACKEND_NAMES:
        raise BackendError(f"unknown backend {name!r}; allowed: {', '.join(BACKEND_NAMES)}")
    if key == "replay":
        if transcript is None:
            raise BackendError("the replay backend needs a transcript to serve (transcript=PATH / --transcript PATH)")
        if kw:
            raise BackendError(f"the replay backend takes no options besides the transcript; got {sorted(kw)}")
        from generator.backends.transcript import ReplayBackend

        replay = ReplayBackend(transcript)
        if model and model != replay.model:
            log.warning("model %r ignored: the transcript %s was recorded with %r", model, transcript, replay.model)
        return replay
    backend: Backend
    if key == "anthropic":
        from generator.backends.anthropic_backend import AnthropicBackend

        backend = AnthropicBackend(model=model, **kw)
    else:
        backend = _make_offline(seed=seed, model=model, **kw)
    if transcript is not None:
        from generator.backends.transcript import RecordingBackend

        return RecordingBackend(backend, transcript, overwrite=overwrite_transcript)
    return backend


def _make_offline(*, seed: int, model: str | None, **kw: Any) -> Backend:
    try:
        module = importlib.import_module(_OFFLINE_MODULE)
    except ModuleNotFoundError as err:
        if err.name != _OFFLINE_MODULE:
            raise
        raise BackendError(f"the offline backend is not available ({_OFFLINE_MODULE} is missing); "
                           f"use --backend anthropic with ANTHROPIC_API_KEY set") from err
    if model:
        log.warning("model %r ignored: the offline backend is not a language model", model)
    return module.OfflineBackend(seed=seed, **kw)
