"""How ``omnibot send`` and ``omnibot console`` print what the controller says: a reply as its text
line, an event (a TEL sample in readable units, a sonar's range, a warning...) on one line.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

from omnibot.client import (
    STATE_NAMES,
    ErrorEvent,
    Event,
    IdleEvent,
    RangeEvent,
    ResetEvent,
    Telemetry,
    Unexpected,
    WarnEvent,
)
from omnibot.protocol import text
from omnibot.protocol.messages import Malformed, Reply


def format_reply(reply: Reply) -> str:
    """A reply as its text line: ``<- OK``, ``<- ERROR,23,unknown command``."""
    return "<- " + text.encode(reply).decode("ascii").rstrip()


def commas(values: Iterable[object]) -> str:
    """``values`` joined by commas, as the protocol writes them."""
    return ",".join(str(v) for v in values)


def format_telemetry(tel: Telemetry) -> str:
    """A TEL sample on one line, in readable units."""
    parts = [f"<- TEL {tel.controller_time:.3f} s"]
    if tel.powers is not None:
        parts.append(f"pwr {commas(tel.powers)}")
    if tel.encoders is not None:
        parts.append(f"enc {commas(tel.encoders)}")
    if tel.tracking:
        parts.append(f"trk {commas(tel.tracking)}")
    if tel.gyro_rate is not None:
        parts.append(f"gyro {math.degrees(tel.gyro_rate):.1f} deg/s")
    if tel.heading is not None:
        parts.append(f"hdg {math.degrees(tel.heading):.1f} deg")
    if tel.battery is not None:
        parts.append(f"bat {tel.battery:.2f} V")
    if tel.state is not None:
        parts.append(f"{STATE_NAMES.get(tel.state, tel.state)} q{tel.queued}")
    if tel.ranges is not None:
        ranges = ["-" if r is None else f"{round(r * 100)}cm" for r in tel.ranges]
        parts.append(f"sonar {commas(ranges)}")
    return " ".join(parts)


def format_event(event: Event) -> str:
    """An event on one line: ``<- RANGE sonar 1: 42 cm``, ``<- WARN 13 emergency stop by sonar``."""
    if isinstance(event, RangeEvent):
        where = "no echo" if event.distance is None else f"{round(event.distance * 100)} cm"
        return f"<- RANGE sonar {event.sonar}: {where}"
    if isinstance(event, WarnEvent):
        return f"<- WARN {event.code} {event.text}"
    if isinstance(event, ErrorEvent):
        return f"<- ERROR {event.code} {event.text} (no command waiting)"
    if isinstance(event, IdleEvent):
        return "<- IDLE"
    if isinstance(event, Telemetry):
        return format_telemetry(event)
    if isinstance(event, ResetEvent):
        h = event.hello
        return f"<- HELLO,{h.version},{h.name},{h.motors} (controller reset)"
    if isinstance(event, Unexpected):
        msg = event.message
        raw = msg.raw if isinstance(msg, Malformed) else msg
        return f"<- ?? {event.reason}: {raw!r}"
    return f"<- {event}"
