"""The critic's directive grammar: parse edit directives out of a critic's answer and apply them to a TaskSpec.

A directive edits one object of the scene by plain arithmetic; no model is involved in applying it. One directive
per line::

    Scale_Action: <object> - <factor>                        scale_new = scale_old * factor   (factor > 0)
    Position_Action: <object> - move_x|move_y|move_z <metres>   pos_m[axis] += metres
    Pose_Action: <object> - rotate_x|rotate_y|rotate_z <degrees> q_new = R(axis, degrees) * q_old

Semantics, precisely:

* ``Scale_Action`` takes a **factor**, not an absolute scale: ``0.5`` halves the object, ``2`` doubles it. Scaling
  keeps ``pos_m`` (so the object's lowest point keeps its clearance and its footprint centre stays put). A result
  outside :data:`~gendex_envs.spec.SCALE_RANGE` is **rejected** with :class:`~generator.errors.DirectiveError`
  (naming the object, the resulting scale, the range and the factors that would stay inside it) rather than
  clamped: a silently clamped edit would not be the edit the critic asked for, and the error text can be fed back.
* ``Position_Action`` adds metres to the world position ``pos_m``; ``move_z`` changes the clearance of the lowest
  point above the table (``pos_m[2]``), which is clamped at ``>= 0`` (an object cannot be pushed into the table).
* ``Pose_Action`` composes a rotation about the **world** axis with the current orientation
  (``q_new = R(axis, deg) * q_old``, Hamilton product, wxyz) and renormalises it. ``pos_m`` is kept, so the object's
  footprint centre and the clearance of its (new) lowest point stay what they were.

The parser is tolerant of layout: keywords are case-insensitive, surrounding whitespace, list bullets (``-``, ``*``,
``+``, ``1.``), markdown backticks and ``**bold**`` are ignored, ``m`` / ``deg`` units after the value are allowed,
and so are an en/em dash for the hyphen, a missing colon after the keyword (when the rest of the line parses) and a
trailing ``# comment``. ``Scale_Action: none`` (or ``n/a``) is a skipped no-op. Lines that are not directives are
skipped, but a line that *starts* like one (``Scale_Action:``, ``Position_Action:``, ``Pose_Action:``) and does not
parse raises DirectiveError naming the line and the allowed forms. Object names are matched case-insensitively
against the scene's objects.
"""

from __future__ import annotations

import copy
import logging
import math
import re
from collections.abc import Collection, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Literal, NoReturn

from gendex_envs.errors import TaskSpecError, suggest
from gendex_envs.spec import SCALE_RANGE, TaskSpec, parse_task_spec, spec_to_dict
from generator.errors import DirectiveError

log = logging.getLogger(__name__)

DirectiveKind = Literal["scale", "position", "pose"]

KEYWORDS: dict[str, str] = {"scale": "Scale_Action", "position": "Position_Action", "pose": "Pose_Action"}
"""Directive kind -> its canonical keyword."""
MOVE_OPS: tuple[str, ...] = ("move_x", "move_y", "move_z")
ROTATE_OPS: tuple[str, ...] = ("rotate_x", "rotate_y", "rotate_z")
AXIS_INDEX = {"x": 0, "y": 1, "z": 2}

FORMS = ("Scale_Action: <object> - <factor>   (factor > 0 multiplies the current scale: 0.5 halves it)\n"
         "Position_Action: <object> - move_x|move_y|move_z <metres>   (added to pos_m; move_z changes the clearance)\n"
         "Pose_Action: <object> - rotate_x|rotate_y|rotate_z <degrees>   (rotation about the world axis)")
"""The allowed forms, as quoted in error messages."""

_NUMBER = r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?"
_DASH = r"\s*[-\u2013\u2014]\s*"  # hyphen, en dash, em dash
_OBJ = r"(?P<obj>[A-Za-z_][A-Za-z0-9_]*)"
_HEAD = re.compile(r"^(?P<kw>scale|position|pose)[ _]?action\s*:\s*(?P<body>.*)$", re.IGNORECASE)
_HEAD_NO_COLON = re.compile(r"^(?P<kw>scale|position|pose)[ _]?action\s+(?P<body>.*)$", re.IGNORECASE)
_BODY = {
    "scale": re.compile(rf"^{_OBJ}{_DASH}(?:x\s*)?(?P<val>{_NUMBER})\s*(?:x)?$", re.IGNORECASE),
    "position": re.compile(rf"^{_OBJ}{_DASH}(?P<op>move_[a-z]+)\s*[:=]?\s*(?P<val>{_NUMBER})\s*"
                           r"(?:m|metres|meters)?$", re.IGNORECASE),
    "pose": re.compile(rf"^{_OBJ}{_DASH}(?P<op>rotate_[a-z]+)\s*[:=]?\s*(?P<val>{_NUMBER})\s*"
                       r"(?:deg|degrees|\u00b0)?$", re.IGNORECASE),
}
NO_OP_BODIES = frozenset({"none", "n/a", "na", "-", "no change", "nothing"})
"""Bodies that say "no edit of this kind" (``Scale_Action: none``); such lines are skipped, not errors."""
_BULLET = re.compile(r"^(?:[-*+\u2022]\s+|\d+[.)]\s+)")


@dataclass(frozen=True)
class Directive:
    """One parsed directive. ``str(d)`` is its canonical line, and parsing that line gives ``d`` back."""

    kind: DirectiveKind
    """``scale``, ``position`` or ``pose``."""
    object: str
    """Name of the scene object it edits."""
    op: str
    """``scale``; ``move_x|move_y|move_z``; ``rotate_x|rotate_y|rotate_z``."""
    value: float
    """Scale factor (> 0); metres; degrees."""
    line: str = field(default="", compare=False)
    """The source line it was parsed from ('' for directives made in code); not part of equality."""

    def __post_init__(self) -> None:
        allowed = {"scale": ("scale",), "position": MOVE_OPS, "pose": ROTATE_OPS}.get(self.kind)
        if allowed is None:
            raise DirectiveError(f"unknown directive kind {self.kind!r}; allowed: {', '.join(KEYWORDS)}")
        if self.op not in allowed:
            raise DirectiveError(f"{KEYWORDS[self.kind]} has no operation {self.op!r}; allowed: {', '.join(allowed)}")
        if not math.isfinite(self.value):
            raise DirectiveError(f"{KEYWORDS[self.kind]} for {self.object!r}: value {self.value!r} is not finite")
        if self.kind == "scale" and self.value <= 0:
            raise DirectiveError(f"Scale_Action for {self.object!r}: factor {self.value!r} must be > 0 "
                                 f"(it multiplies the current scale: 0.5 halves it, 2 doubles it)")

    def __str__(self) -> str:
        value = _fmt(self.value)
        if self.kind == "scale":
            return f"Scale_Action: {self.object} - {value}"
        return f"{KEYWORDS[self.kind]}: {self.object} - {self.op} {value}"

    @classmethod
    def scale(cls, obj: str, factor: float) -> Directive:
        return cls("scale", obj, "scale", float(factor))

    @classmethod
    def move(cls, obj: str, axis: str, metres: float) -> Directive:
        return cls("position", obj, f"move_{axis}", float(metres))

    @classmethod
    def rotate(cls, obj: str, axis: str, degrees: float) -> Directive:
        return cls("pose", obj, f"rotate_{axis}", float(degrees))


def _fmt(value: float) -> str:
    """Shortest text that parses back to exactly ``value`` (``0.05``, ``90.0``, ``1e-05``)."""
    return repr(float(value))


def _clean(line: str) -> str:
    """Strip whitespace, markdown backticks / bold and a leading list bullet."""
    text = line.replace("`", "").replace("**", "").strip()
    text = _BULLET.sub("", text, count=1).strip()
    return text


def _malformed(line: str, why: str) -> DirectiveError:
    return DirectiveError(f"malformed directive {line.strip()!r}: {why}. Allowed forms (one per line):\n{FORMS}")


def _resolve_object(token: str, names: Collection[str], line: str) -> str:
    if token in names:
        return token
    lowered = {n.lower(): n for n in names}
    if token.lower() in lowered:
        return lowered[token.lower()]
    listed = ", ".join(sorted(names)) or "none"
    raise DirectiveError(f"directive {line.strip()!r} names object {token!r}, which is not in the scene; "
                         f"objects: {listed}.{suggest(token, names) or suggest(token.lower(), names)}")


def parse_directive_line(line: str, object_names: Collection[str]) -> Directive | None:
    """The directive on ``line``; None when the line is not a directive; DirectiveError when it is a bad one."""
    text = _clean(line)
    if "#" in text:
        text = text.split("#", 1)[0].strip()
    head = _HEAD.match(text)
    if head is None:
        # without the colon the line is only a directive if the rest parses (else it is prose: "Scale action is ...")
        loose = _HEAD_NO_COLON.match(text)
        if loose is None or _BODY[loose.group("kw").lower()].match(loose.group("body").strip().rstrip(".;,")) is None:
            return None
        head = loose
    kind = head.group("kw").lower()
    body = head.group("body").strip().rstrip(".;,").strip()
    if body.lower() in NO_OP_BODIES:
        return None
    m = _BODY[kind].match(body)
    if m is None:
        _diagnose(kind, body, line, object_names)
    obj = _resolve_object(m.group("obj"), object_names, line)
    value = float(m.group("val"))
    if kind == "scale":
        op = "scale"
    else:
        op = m.group("op").lower()
        allowed = MOVE_OPS if kind == "position" else ROTATE_OPS
        if op not in allowed:
            raise _malformed(line, f"{KEYWORDS[kind]} has no operation {op!r}; allowed: {', '.join(allowed)}"
                                   f"{suggest(op, allowed)}")
    if not math.isfinite(value):
        raise _malformed(line, f"value {m.group('val')!r} is not a finite number")
    if kind == "scale" and value <= 0:
        raise _malformed(line, f"the scale factor must be > 0 (got {value!r}; it multiplies the current scale)")
    return Directive(kind, obj, op, value, line=line.strip())


def _diagnose(kind: str, body: str, line: str, object_names: Collection[str]) -> NoReturn:
    """Raise the most helpful DirectiveError for a directive line whose body did not match its form."""
    if not body:
        raise _malformed(line, "nothing after the keyword")
    first = re.match(r"^([A-Za-z_][A-Za-z0-9_]*)\s*[-\u2013\u2014]", body)
    if first is not None and first.group(1) not in object_names and \
            first.group(1).lower() not in {n.lower() for n in object_names}:
        _resolve_object(first.group(1), object_names, line)  # raises: unknown object, with a suggestion
    ops = {"position": MOVE_OPS, "pose": ROTATE_OPS}.get(kind)
    if ops is not None:
        op = re.search(r"\b([a-z]+_[a-z]+)\b", body, re.IGNORECASE)
        if op is not None and op.group(1).lower() not in ops:
            raise _malformed(line, f"{KEYWORDS[kind]} has no operation {op.group(1)!r}; allowed: {', '.join(ops)}"
                                   f"{suggest(op.group(1).lower(), ops)}")
    raise _malformed(line, f"expected the form {FORMS.splitlines()[list(KEYWORDS).index(kind)].split('   ')[0]!r}")


def parse_directives(text: str, object_names: Iterable[str]) -> list[Directive]:
    """Every directive in ``text``, in order; other lines are ignored. Raises DirectiveError on a bad directive."""
    names = list(object_names)
    out = []
    for line in text.splitlines():
        d = parse_directive_line(line, names)
        if d is not None:
            out.append(d)
    log.debug("parsed %d directives", len(out))
    return out


# ------------------------------------------------------------------------------------------- arithmetic
def quat_mul_wxyz(a: Iterable[float], b: Iterable[float]) -> tuple[float, float, float, float]:
    """Hamilton product a * b of (w, x, y, z) quaternions (apply b, then a)."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw)


def axis_quat(axis: str, degrees: float) -> tuple[float, float, float, float]:
    """Unit quaternion (w, x, y, z) of a rotation by ``degrees`` about world axis ``axis`` ('x', 'y' or 'z')."""
    half = math.radians(degrees) / 2
    q = [math.cos(half), 0.0, 0.0, 0.0]
    q[1 + AXIS_INDEX[axis]] = math.sin(half)
    return tuple(q)


def _normalise(q: Iterable[float]) -> list[float]:
    q = list(q)
    n = math.sqrt(sum(v * v for v in q))
    q = [v / n for v in q]
    if q[0] < 0:  # canonical hemisphere: w >= 0 (same rotation)
        q = [-v for v in q]
    return q


def _apply_one(raw: dict, d: Directive) -> None:
    objects = raw.get("objects") or []
    matches = [o for o in objects if isinstance(o, Mapping) and o.get("name") == d.object]
    if not matches:
        names = [o.get("name") for o in objects if isinstance(o, Mapping)]
        raise DirectiveError(f"directive {str(d)!r} names object {d.object!r}, which is not in the scene; objects: "
                             f"{', '.join(map(str, names))}.{suggest(d.object, [str(n) for n in names])}")
    obj = matches[0]
    if d.kind == "scale":
        old = obj.get("scale", 1.0)
        if isinstance(old, bool) or not isinstance(old, (int, float)):
            raise DirectiveError(f"directive {str(d)!r}: object {d.object!r} has a non-numeric scale {old!r}")
        new = float(old) * d.value
        lo, hi = SCALE_RANGE
        if not lo <= new <= hi:
            raise DirectiveError(
                f"directive {str(d)!r} would give object {d.object!r} scale {old:g} * {d.value:g} = {new:.4g}, "
                f"outside the allowed range {lo} <= scale <= {hi}; factors allowed for it now: "
                f"{lo / old:.4g} to {hi / old:.4g}")
        obj["scale"] = new
    elif d.kind == "position":
        pos = [float(v) for v in obj["pos_m"]]
        i = AXIS_INDEX[d.op[-1]]
        pos[i] += d.value
        if i == 2 and pos[2] < 0:
            log.info("%s: clearance %.4f clamped to 0 (the object rests on the table)", d, pos[2])
            pos[2] = 0.0
        obj["pos_m"] = pos
    else:
        q_old = obj.get("quat_wxyz", (1.0, 0.0, 0.0, 0.0))
        obj["quat_wxyz"] = _normalise(quat_mul_wxyz(axis_quat(d.op[-1], d.value), q_old))


def apply_directives(spec: TaskSpec | Mapping, directives: Iterable[Directive]) -> TaskSpec:
    """A new TaskSpec: ``directives`` applied in order by arithmetic (module docstring), then re-validated.

    ``spec`` may also be a raw task mapping (e.g. one whose out-of-range scale keeps it from parsing; a
    Scale_Action can bring it back). Raises DirectiveError for an unknown object or a scale leaving SCALE_RANGE;
    TaskSpecError if the result is invalid for another reason (one the directives did not fix).
    """
    raw = spec_to_dict(spec) if isinstance(spec, TaskSpec) else copy.deepcopy(dict(spec))
    directives = list(directives)
    for d in directives:
        _apply_one(raw, d)
    name = raw.get("name", "?")
    try:
        out = parse_task_spec(raw, source=f"<{name} after {len(directives)} directives>")
    except TaskSpecError:
        log.debug("spec %s is invalid after directives %s", name, [str(d) for d in directives])
        raise
    log.info("applied %d directives to %s", len(directives), name)
    return out
