"""Helpers shared by the pipeline steps: asking a backend with a rendered prompt, pulling fenced blocks out."""

from __future__ import annotations

import json
import logging
import re
from typing import Any

import yaml

from gendex_envs.typed_yaml import (
    MAX_INPUT_BYTES,
    InputBoundsError,
    parse_json_bounded,
    parse_yaml_bounded,
    yaml_error_text,
)
from generator.backends.base import Backend, ImagePart, ModelRequest
from generator.errors import ModelOutputError
from generator.prompts import render, template

log = logging.getLogger(__name__)

_FENCE = re.compile(r"```([A-Za-z]*)[ \t]*\n(.*?)```", re.S)


def ask(backend: Backend, prompt: str, *, context: dict[str, Any], images: tuple[ImagePart, ...] = (),
        feedback: str = "", **variables: Any) -> str:
    """Render template ``prompt``, append ``feedback`` (why the last answer was rejected), and return the answer."""
    t = template(prompt)
    text = render(prompt, **variables)
    if feedback:
        text += ("\nYour previous answer was rejected for this reason; answer again, fixing it:\n" + feedback + "\n")
    request = ModelRequest(step=t.step, prompt=text, system=render("system"), images=images,
                           temperature=t.temperature, context=context)
    return backend.complete(request).text


def fenced(text: str, lang: str) -> str:
    """The body of the first ```lang fenced block (or of the first fence of any language, or the whole text)."""
    blocks = _FENCE.findall(text)
    for tag, body in blocks:
        if tag.lower() == lang:
            return body
    if blocks:
        return blocks[0][1]
    return text


def _check_reply_size(text: str, what: str, error: type[ModelOutputError]) -> None:
    size = len(text) if len(text) > MAX_INPUT_BYTES else len(text.encode("utf-8", "surrogatepass"))
    if size > MAX_INPUT_BYTES:
        raise error(f"the {what} is {size} bytes; at most {MAX_INPUT_BYTES} bytes are allowed (MAX_INPUT_BYTES)")


def parse_json_block(text: str, what: str, error: type[ModelOutputError] = ModelOutputError) -> Any:
    """The JSON of a model reply's ```json block, parsed within the bounds of untrusted input
    (:func:`~gendex_envs.typed_yaml.parse_json_bounded`); any failure raises ``error``."""
    _check_reply_size(text, what, error)
    body = fenced(text, "json").strip()
    if not body.startswith(("{", "[")):
        start = body.find("{")
        body = body[start:] if start >= 0 else body
    try:
        return parse_json_bounded(body, f"the {what}")
    except json.JSONDecodeError as exc:
        raise error(f"the {what} is not valid JSON: {exc.msg} at line {exc.lineno} column {exc.colno}") from None
    except InputBoundsError as exc:
        raise error(f"the {what} is refused: {exc.problem}") from None


def parse_yaml_block(text: str, what: str, error: type[ModelOutputError] = ModelOutputError) -> Any:
    """The YAML of a model reply's ```yaml block, parsed within the bounds of untrusted input (no anchors or
    aliases, capped size, depth, node count and string length: :func:`~gendex_envs.typed_yaml.parse_yaml_bounded`);
    any failure raises ``error``."""
    _check_reply_size(text, what, error)
    body = fenced(text, "yaml")
    try:
        return parse_yaml_bounded(body, f"the {what}")
    except yaml.YAMLError as exc:
        where, problem = yaml_error_text(exc)
        kind = "is refused" if isinstance(exc, InputBoundsError) else "is not valid YAML"
        raise error(f"the {what} {kind}{where.replace(',', '')}: {problem}") from None
