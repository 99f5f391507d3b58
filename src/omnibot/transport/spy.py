"""Trace wrapper (``spy+<url>``): records every write and read of a link, passing bytes through.

Each event is a :class:`SpyEvent` handed to a callback, or formatted as hexdump lines into a text
stream or file. Timestamps come from the link's clock, relative to when the spy was opened, so a
trace of a lockstep link shows simulated time and is the same on every run::

    0.001000 TX   0000  48 45 4C 4C 4F 0A                                 HELLO.
    0.004000 RX   0000  48 45 4C 4C 4F 2C 32 2C 6F 6D 6E 69 34 2C 34 0D  HELLO,2,omni4,4.
    0.004000 RX   0010  0A                                                .
    0.104000 RX   <timeout>
    0.105000 ERR  serial port /dev/ttyUSB0 failed: ...

Kinds: ``TX`` (host wrote), ``RX`` (host read), ``RX`` with ``<timeout>`` (an empty read; only with
``all_reads=True``, URL option ``all``), ``ERR`` (a LinkError went by), ``CLOSE``.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Literal, TextIO

from omnibot.errors import LinkError
from omnibot.transport.base import Clock, Link

__all__ = ["SpyEvent", "SpyLink", "format_event", "hexdump"]

Kind = Literal["TX", "RX", "ERR", "CLOSE"]


@dataclass(frozen=True)
class SpyEvent:
    """One traced event: clock time (s since the spy opened), kind, bytes, and a note for ERR."""

    time: float
    kind: Kind
    data: bytes = b""
    note: str = ""


def hexdump(data: bytes, width: int = 16) -> Iterator[str]:
    """Yield ``"OFFS  HH HH ...  ascii"`` rows, ``width`` bytes per row."""
    for offset in range(0, len(data), width):
        row = data[offset : offset + width]
        hexes = " ".join(f"{b:02X}" for b in row)
        text = "".join(chr(b) if 32 <= b < 127 else "." for b in row)
        yield f"{offset:04X}  {hexes:<{3 * width - 1}}  {text}"


def format_event(event: SpyEvent) -> list[str]:
    """The text lines for one event (several for long data)."""
    head = f"{event.time:10.6f} {event.kind:<4}"
    if event.kind in ("TX", "RX") and event.data:
        return [f"{head} {row}" for row in hexdump(event.data)]
    if event.kind == "RX":
        return [f"{head} <timeout>"]
    return [f"{head} {event.note}".rstrip()]


Sink = Callable[[SpyEvent], None] | TextIO


class SpyLink(Link):
    """Wraps ``inner``; every event goes to ``sink`` (a callback or text stream; default stderr).

    ``all_reads=True`` also records reads that timed out empty. If ``owns_sink`` the stream is closed with
    the link (used for ``file=`` in URLs).
    """

    def __init__(
        self,
        inner: Link,
        sink: Sink | None = None,
        *,
        all_reads: bool = False,
        owns_sink: bool = False,
        url: str | None = None,
    ) -> None:
        super().__init__(url or f"spy+{inner.url}", inner.clock)
        self.inner = inner
        self.all_reads = all_reads
        self._stream: TextIO | None = None
        self._callback: Callable[[SpyEvent], None]
        if sink is None:
            sink = sys.stderr
        if callable(sink):
            self._callback = sink
        else:
            self._stream = sink
            self._callback = self._print
        self._owns_sink = owns_sink and self._stream is not None
        self._t0 = inner.clock.now()

    @property
    def clock(self) -> Clock:
        """The wrapped link's clock."""
        return self.inner.clock

    def line_time(self, size: int) -> float:
        """The wrapped link's (see :meth:`Link.line_time`)."""
        return self.inner.line_time(size)

    def reopen(self, retry: float | None = None) -> None:
        """Reopen the wrapped link (LinkError if this one was closed)."""
        self._check_open()
        self.inner.reopen(retry)

    def _print(self, event: SpyEvent) -> None:
        assert self._stream is not None
        for line in format_event(event):
            self._stream.write(line + "\n")
        self._stream.flush()

    def _emit(self, kind: Kind, data: bytes = b"", note: str = "") -> None:
        self._callback(SpyEvent(self.inner.clock.now() - self._t0, kind, data, note))

    def _write(self, data: bytes) -> None:
        self._emit("TX", data)
        try:
            self.inner.write(data)
        except LinkError as exc:
            self._emit("ERR", note=str(exc))
            raise

    def _read(self, max_bytes: int, timeout: float | None) -> bytes:
        try:
            data = self.inner.read(max_bytes, timeout)
        except LinkError as exc:
            self._emit("ERR", note=str(exc))
            raise
        if data or self.all_reads:
            self._emit("RX", data)
        return data

    def _close(self) -> None:
        try:
            self._emit("CLOSE")
            self.inner.close()
        finally:
            if self._owns_sink and self._stream is not None:
                self._stream.close()
