"""Events from the controller, in SI, and the listeners they fan out to (python-can Notifier style).

::

    Event                 time: the link clock (s) when the client decoded it; message: the raw message
     +-- RangeEvent       RANGE: a sonar reading met its band (sonar numbered 1..k, distance m)
     +-- WarnEvent        WARN,<code>,<text> (11 speed reduced, 12 power too low, 13 sonar e-stop)
     +-- ErrorEvent       an ERROR no command was waiting for (binary: an ERROR event frame)
     +-- IdleEvent        IDLE: the queue ran empty and the motors stopped
     +-- Telemetry        TEL: one telemetry sample
     +-- ResetEvent       HELLO unasked: the controller (re)started
     +-- Unexpected       a malformed line or frame, or a reply nobody was waiting for

:class:`Listeners` keeps ``(callback, types)`` pairs and calls each callback with the events of its
types, in the thread that pumps the client. :class:`EventRecorder` is a listener that keeps them.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar

from omnibot.client.views import Hello
from omnibot.protocol import units
from omnibot.protocol.messages import (
    ErrorReply,
    HelloReply,
    Idle,
    Malformed,
    Message,
    Range,
    Warn,
)
from omnibot.protocol.messages import (
    Telemetry as TelMessage,
)

log = logging.getLogger("omnibot.client")


@dataclass(frozen=True, kw_only=True)
class Event:
    """Something the controller sent that is not a reply to a command."""

    time: float
    """The link clock (s) when the client decoded it."""
    message: Message | Malformed | None = None
    """The protocol message (or Malformed bytes) it came from."""


@dataclass(frozen=True, kw_only=True)
class RangeEvent(Event):
    """``RANGE``: a sonar reading inside its band."""

    sonar: int
    """Sonar number, 1..k as in the protocol."""
    distance: float | None
    """Range in m; None when the sonar had no echo (-1 cm)."""


@dataclass(frozen=True, kw_only=True)
class WarnEvent(Event):
    """``WARN``: a warning of the motion or sensor logic, its code and text."""

    code: int
    text: str


@dataclass(frozen=True, kw_only=True)
class ErrorEvent(Event):
    """``ERROR`` as an event: a fault of the motion logic, its code and text."""

    code: int
    text: str


@dataclass(frozen=True, kw_only=True)
class IdleEvent(Event):
    """``IDLE``: the queue ran empty and the motors stopped."""

    pass


@dataclass(frozen=True, kw_only=True)
class ResetEvent(Event):
    """HELLO unasked: the controller (re)started; ``hello`` says what it is."""

    hello: Hello


@dataclass(frozen=True, kw_only=True)
class Unexpected(Event):
    """Bytes that were no valid message, or a reply nobody was waiting for; ``reason`` says which."""

    reason: str


@dataclass(frozen=True, kw_only=True)
class Telemetry(Event):
    """A TEL sample in SI; groups the TELEM mask left out are None.

    ``controller_time`` s since the controller's boot (wraps at 2**32 ms); ``powers`` raw counts
    (-255..255); ``encoders``/``tracking`` cumulative counts; ``gyro_rate`` rad/s and ``heading``
    rad (counter-clockwise positive, heading not wrapped); ``battery`` V; ``state`` (0 moving,
    1 idle, 3 e-stop) and ``queued`` commands; ``ranges`` m per sonar (None: no reading).
    """

    controller_time: float
    powers: tuple[int, ...] | None = None
    encoders: tuple[int, ...] | None = None
    tracking: tuple[int, ...] | None = None
    gyro_rate: float | None = None
    heading: float | None = None
    battery: float | None = None
    state: int | None = None
    queued: int | None = None
    ranges: tuple[float | None, ...] | None = None

    @classmethod
    def from_message(cls, tel: TelMessage, time: float) -> Telemetry:
        """The sample of a TEL message in SI units, decoded at link time ``time`` s."""
        return cls(
            time=time,
            message=tel,
            controller_time=units.from_ms(tel.t_ms),
            powers=tel.powers,
            encoders=tel.encoders,
            tracking=tel.tracking,
            gyro_rate=None if tel.gyro_rate is None else units.from_centideg(tel.gyro_rate),
            heading=None if tel.heading is None else units.from_centideg(tel.heading),
            battery=None if tel.battery_mv is None else units.from_mv(tel.battery_mv),
            state=None if tel.queue is None else tel.queue[0],
            queued=None if tel.queue is None else tel.queue[1],
            ranges=None if tel.ranges is None else tuple(_metres(r) for r in tel.ranges),
        )


def _metres(cm: int) -> float | None:
    return None if cm < 0 else units.from_cm(cm)


def event_from_message(message: Message | Malformed, time: float) -> Event:
    """The Event for an event message (a reply here is Unexpected: nobody was waiting for it)."""
    if isinstance(message, Malformed):
        return Unexpected(time=time, message=message, reason=message.reason)
    if isinstance(message, TelMessage):
        return Telemetry.from_message(message, time)
    if isinstance(message, Range):
        return RangeEvent(time=time, message=message, sonar=message.sonar, distance=_metres(message.cm))
    if isinstance(message, Warn):
        return WarnEvent(time=time, message=message, code=message.code, text=message.description)
    if isinstance(message, ErrorReply):
        return ErrorEvent(time=time, message=message, code=message.code, text=message.description)
    if isinstance(message, Idle):
        return IdleEvent(time=time, message=message)
    if isinstance(message, HelloReply):
        return ResetEvent(time=time, message=message, hello=Hello.from_reply(message))
    return Unexpected(time=time, message=message, reason=f"{message.keyword} nobody was waiting for")


E = TypeVar("E", bound=Event)
Listener = Callable[[E], object]


class Listeners:
    """Callbacks per event type. A callback that raises is logged and the others still run."""

    def __init__(self) -> None:
        self._entries: list[tuple[Callable[[Event], object], tuple[type[Event], ...]]] = []

    def add(self, callback: Callable[[E], object], *types: type[E]) -> None:
        """Call ``callback(event)`` for events of ``types`` (every event if none are given)."""
        self._entries.append((callback, types or (Event,)))  # type: ignore[arg-type]

    def remove(self, callback: Callable[[E], object]) -> None:
        """Forget every registration of ``callback`` (no error if there is none)."""
        self._entries = [
            e for e in self._entries if e[0] != callback
        ]  # a bound method is a new object each time

    def dispatch(self, event: Event) -> None:
        """Call every callback registered for the type of ``event``."""
        for callback, types in list(self._entries):
            if isinstance(event, types):
                try:
                    callback(event)
                except Exception:
                    log.exception("event listener %r failed on %r", callback, event)


class EventRecorder:
    """A listener that keeps every event it gets: ``client.add_listener(rec := EventRecorder())``."""

    def __init__(self) -> None:
        self.events: list[Event] = []

    def __call__(self, event: Event) -> None:
        """Keep ``event``."""
        self.events.append(event)

    def of(self, kind: type[E]) -> list[E]:
        """The recorded events of one type, oldest first."""
        return [e for e in self.events if isinstance(e, kind)]

    def clear(self) -> None:
        """Forget the recorded events."""
        self.events.clear()
