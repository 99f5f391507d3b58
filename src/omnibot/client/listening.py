"""Events and telemetry: who hears them (docs/client.md, "Events").

:class:`Listening` is the client's registration of listeners (called, in the caller's thread, with
the events that arrive during the client's waits) and tracers (a recorder: the link's bytes, the
commands and replies).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

from omnibot.client.core import ClientCore
from omnibot.client.events import ErrorEvent, Event, IdleEvent, RangeEvent, ResetEvent, Telemetry, WarnEvent
from omnibot.client.tracing import Tracer

E = TypeVar("E", bound=Event)


class Listening(ClientCore):
    """add_listener, remove_listener, add_tracer, remove_tracer and the on_* shorthands."""

    def add_listener(self, callback: Callable[[E], object], *types: type[E]) -> None:
        """Call ``callback(event)`` for each event of ``types`` (all events if none are given)."""
        self._listeners.add(callback, *types)

    def remove_listener(self, callback: Callable[[E], object]) -> None:
        """Stop calling ``callback`` (no error if it was not listening)."""
        self._listeners.remove(callback)

    def add_tracer(self, tracer: Tracer) -> None:
        """Hand ``tracer`` the link's bytes and the commands and replies (a recorder)."""
        self._tracers.add(tracer)

    def remove_tracer(self, tracer: Tracer) -> None:
        """Stop handing ``tracer`` anything."""
        self._tracers.remove(tracer)

    def on_telemetry(self, callback: Callable[[Telemetry], object]) -> None:
        """Call ``callback`` with every TEL sample."""
        self._listeners.add(callback, Telemetry)

    def on_range(self, callback: Callable[[RangeEvent], object]) -> None:
        """Call ``callback`` with every RANGE event."""
        self._listeners.add(callback, RangeEvent)

    def on_warn(self, callback: Callable[[WarnEvent], object]) -> None:
        """Call ``callback`` with every WARN event."""
        self._listeners.add(callback, WarnEvent)

    def on_error(self, callback: Callable[[ErrorEvent], object]) -> None:
        """Call ``callback`` with every ERROR event (a fault of the motion logic, not a rejected command)."""
        self._listeners.add(callback, ErrorEvent)

    def on_idle(self, callback: Callable[[IdleEvent], object]) -> None:
        """Call ``callback`` with every IDLE event (the queue ran empty, the motors stopped)."""
        self._listeners.add(callback, IdleEvent)

    def on_reset(self, callback: Callable[[ResetEvent], object]) -> None:
        """Call ``callback`` when the controller resets (its HELLO line arrives unasked)."""
        self._listeners.add(callback, ResetEvent)
