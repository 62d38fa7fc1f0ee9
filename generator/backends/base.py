"""The backend interface: a :class:`ModelRequest` (text, optional images) in, a :class:`ModelResponse` out.

Pipeline steps render a prompt template into ``prompt`` and put the typed inputs the prompt was made from into
``context`` (JSON-able). Language-model backends send ``system``, ``prompt`` and ``images`` and ignore ``context``;
the offline backend answers from ``context`` alone. Both answer in the same text format, so every answer goes
through the same parser and validator.
"""

from __future__ import annotations

import base64
import hashlib
import json
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

STEPS = ("propose", "propose_guided", "scene", "analyze", "plan", "reward")
"""Request kinds (the pipeline step asking); the offline backend dispatches on them, transcripts record them."""


@dataclass(frozen=True)
class ImagePart:
    """One PNG image sent with a request (e.g. a rendered view)."""

    name: str
    png: bytes

    def b64(self) -> str:
        return base64.b64encode(self.png).decode("ascii")

    def sha256(self) -> str:
        """Hex SHA-256 of the PNG bytes (transcripts store this instead of the image)."""
        return hashlib.sha256(self.png).hexdigest()


@dataclass(frozen=True)
class ModelRequest:
    """One request to a backend."""

    step: str
    """The pipeline step asking; one of STEPS."""
    prompt: str
    """The rendered user prompt."""
    system: str = ""
    images: tuple[ImagePart, ...] = ()
    temperature: float = 0.3
    max_tokens: int = 4096
    context: dict[str, Any] = field(default_factory=dict)
    """Structured inputs the prompt was rendered from (JSON-able); used by the offline backend only."""

    def __post_init__(self) -> None:
        if self.step not in STEPS:
            raise ValueError(f"unknown request step {self.step!r}; allowed: {', '.join(STEPS)}")

    def digest(self) -> str:
        """SHA-256 over everything that defines the request (replay checks it)."""
        h = hashlib.sha256()
        head = {"step": self.step, "system": self.system, "prompt": self.prompt, "temperature": self.temperature,
                "max_tokens": self.max_tokens, "context": self.context}
        h.update(json.dumps(head, sort_keys=True, default=str).encode())
        for im in self.images:
            h.update(im.name.encode())
            h.update(hashlib.sha256(im.png).digest())
        return h.hexdigest()

    def to_record(self) -> dict[str, Any]:
        """A JSON-able summary of the request for transcripts: every field, but images by name, SHA-256 and size.

        ``context`` goes through the same ``json.dumps(default=str)`` as :meth:`digest`, so what is stored is what
        was hashed. The record cannot be turned back into a request (the image bytes are not in it).
        """
        return {
            "step": self.step,
            "system": self.system,
            "prompt": self.prompt,
            "temperature": self.temperature,
            "max_tokens": self.max_tokens,
            "context": json.loads(json.dumps(self.context, sort_keys=True, default=str)),
            "images": [{"name": im.name, "sha256": im.sha256(), "bytes": len(im.png)} for im in self.images],
        }


@dataclass(frozen=True)
class ModelResponse:
    """A backend's answer."""

    text: str
    backend: str
    model: str
    usage: dict[str, int] = field(default_factory=dict)

    def to_record(self) -> dict[str, Any]:
        """JSON-able form (transcripts); :meth:`from_record` reads it back unchanged."""
        return {"text": self.text, "backend": self.backend, "model": self.model, "usage": dict(self.usage)}

    @classmethod
    def from_record(cls, record: Any) -> ModelResponse:
        """Inverse of :meth:`to_record`; raises ``TypeError`` naming the first field that is missing or mistyped."""
        if not isinstance(record, dict):
            raise TypeError(f"a response record must be an object, got {type(record).__name__}")
        for key in ("text", "backend", "model"):
            if not isinstance(record.get(key), str):
                raise TypeError(f"response field {key!r} must be a string, got {record.get(key)!r:.80}")
        usage = record.get("usage", {})
        if not isinstance(usage, dict) or not all(isinstance(k, str) and isinstance(v, int) for k, v in usage.items()):
            raise TypeError(f"response field 'usage' must map names to integers, got {usage!r:.80}")
        return cls(text=record["text"], backend=record["backend"], model=record["model"], usage=dict(usage))


@runtime_checkable
class Backend(Protocol):
    """What every backend provides."""

    name: str
    model: str
    sees_images: bool
    """True when the backend looks at ``ModelRequest.images`` (the vision critic runs only then)."""
    is_language_model: bool

    def complete(self, request: ModelRequest) -> ModelResponse: ...
