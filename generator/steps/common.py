"""Helpers shared by the pipeline steps: asking a backend with a rendered prompt, pulling fenced blocks out."""

from __future__ import annotations

import json
import logging
import re
from typing import Any

import yaml

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


def parse_json_block(text: str, what: str, error: type[ModelOutputError] = ModelOutputError) -> Any:
    body = fenced(text, "json").strip()
    if not body.startswith(("{", "[")):
        start = body.find("{")
        body = body[start:] if start >= 0 else body
    try:
        return json.loads(body)
    except json.JSONDecodeError as exc:
        raise error(f"the {what} is not valid JSON: {exc.msg} at line {exc.lineno} column {exc.colno}") from None


def parse_yaml_block(text: str, what: str, error: type[ModelOutputError] = ModelOutputError) -> Any:
    body = fenced(text, "yaml")
    try:
        return yaml.safe_load(body)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1} column {mark.column + 1}" if mark else ""
        raise error(f"the {what} is not valid YAML{where}: {getattr(exc, 'problem', exc)}") from None
