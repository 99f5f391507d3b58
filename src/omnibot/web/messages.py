"""Messages from the browser, validated before anything acts on them (pydantic, extra keys forbidden).

Every websocket text frame is one JSON object with a ``type``::

    {"type": "drive", "vx": 0.5, "vy": 0, "w": 0, "enable": true}   fractions (-1..1) of the limits;
                                                                     enable false: let go (deadman)
    {"type": "joy", "axes": [...], "buttons": [...]}                 a gamepad (Gamepad API, standard
                                                                     layout), mapped like a pad
    {"type": "estop"}                                                STOP now; drive ignored until
    {"type": "resume"}                                               resume
    {"type": "teach", "action": "record" | "stop" | "follow"}        teach and repeat (a hook)
    {"type": "ping", "t": 123.4}                                     answered with a pong (latency)

:func:`parse_message` returns the message or a one-line reason it was rejected (which the page
shows); a rejected message is never acted on. Frames larger than :data:`MAX_FRAME` are rejected
unread, and so is JSON nested deeper than :data:`MAX_DEPTH` (checked before it is parsed). Types are
strict: a number must be a JSON number (not ``"1"`` or ``true``), finite (``NaN``, ``Infinity`` and
``1e999`` are refused), and a flag a JSON boolean.
"""

from __future__ import annotations

import json
import math
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, TypeAdapter, ValidationError

MAX_FRAME = 4096
"""Characters: the largest message the page sends is a gamepad's state, well under this."""
MAX_DEPTH = 4
"""Nesting of JSON arrays and objects: a message is an object holding at most lists of numbers (2)."""

Fraction = Annotated[float, Field(ge=-1.0, le=1.0, allow_inf_nan=False)]


class _Message(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)


class Drive(_Message):
    """On-screen joystick or keys: fractions of the robot's speed and turn-rate limits."""

    type: Literal["drive"]
    vx: Fraction = 0.0
    vy: Fraction = 0.0
    w: Fraction = 0.0
    enable: bool = True
    source: Literal["keyboard", "joystick"] = "keyboard"


class Joy(_Message):
    """A browser gamepad: axes as the Gamepad API gives them (up and left negative), buttons 0..1."""

    type: Literal["joy"]
    axes: Annotated[list[Fraction], Field(max_length=16)]
    buttons: Annotated[
        list[Annotated[float, Field(ge=0.0, le=1.0, allow_inf_nan=False)]], Field(max_length=32)
    ]


class EStop(_Message):
    """The page's emergency stop: STOP now, driving ignored until :class:`Resume`."""

    type: Literal["estop"]


class Resume(_Message):
    """Clear the page's emergency stop; driving needs a fresh input."""

    type: Literal["resume"]


class Teach(_Message):
    """Teach-in: record a path, stop recording, or follow the recorded path."""

    type: Literal["teach"]
    action: Literal["record", "stop", "follow"]


class Ping(_Message):
    """A round-trip probe: the server answers ``pong`` with the page's ``t``."""

    type: Literal["ping"]
    t: float = Field(allow_inf_nan=False)


Message = Annotated[Drive | Joy | EStop | Resume | Teach | Ping, Field(discriminator="type")]
_ADAPTER: TypeAdapter[Message] = TypeAdapter(Message)


def _reason(error: ValidationError) -> str:
    parts = []
    for item in error.errors()[:3]:
        loc = ".".join(str(p) for p in item["loc"])
        msg = item["msg"]
        given = item.get("input")
        if item["type"] == "union_tag_invalid":
            tag = item.get("ctx", {}).get("tag", "")
            msg = f"unknown message type {tag!r}; expected one of: drive, joy, estop, resume, teach, ping"
        elif item["type"] == "union_tag_not_found":
            msg = "a message needs a 'type'"
        elif item["type"] == "extra_forbidden":
            msg = "unknown key"
        elif isinstance(given, int | float | str) and not isinstance(given, bool):
            shown = repr(given)
            msg += f" (got {shown if len(shown) <= 40 else shown[:37] + '...'})"
        parts.append(f"{loc}: {msg}" if loc else msg)
    return "; ".join(parts)


def nesting(text: str) -> int:
    """How deep JSON text nests arrays and objects (brackets inside strings do not count); a scan
    without recursion, so hostile text cannot exhaust the parser's stack."""
    depth = deepest = 0
    in_string = escaped = False
    for ch in text:
        if in_string:
            if escaped:
                escaped = False
            elif ch == "\\":
                escaped = True
            elif ch == '"':
                in_string = False
        elif ch == '"':
            in_string = True
        elif ch in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif ch in "]}":
            depth -= 1
    return deepest


def _no_constant(name: str) -> float:
    raise ValueError(f"{name} is not a number a message may hold")


def _finite(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"{text} is out of range")
    return value


def parse_message(text: str) -> Message | str:
    """The validated message, or why it was rejected."""
    if len(text) > MAX_FRAME:
        return f"message too long ({len(text)} characters, at most {MAX_FRAME})"
    if nesting(text) > MAX_DEPTH:
        return f"message nested too deeply (at most {MAX_DEPTH} levels of arrays and objects)"
    try:
        data = json.loads(text, parse_constant=_no_constant, parse_float=_finite)
    except (ValueError, RecursionError) as exc:
        return f"not JSON: {exc}"
    if not isinstance(data, dict):
        return f"a message is a JSON object, got {type(data).__name__}"
    try:
        return _ADAPTER.validate_python(data)
    except ValidationError as exc:
        return _reason(exc)
