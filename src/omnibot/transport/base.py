"""The byte-link interface every transport implements, and the clock a link carries.

A :class:`Link` moves bytes, nothing else: it knows no protocol and no simulator.

Reading: ``read(max_bytes, timeout)`` returns the bytes that are available (1..max_bytes of them),
waiting up to ``timeout`` seconds for the first one. On timeout it returns ``b""``; it never raises
:class:`~omnibot.errors.LinkTimeout` (request/reply code decides what a silence means and raises that
itself). ``timeout=None`` waits for ever, ``timeout=0`` only takes what is already there.

Failures: a link that cannot be used any more (port unplugged, peer gone, used after ``close()``)
raises :class:`~omnibot.errors.LinkError` from ``read`` and ``write``. ``close()`` from another thread
wakes a reader blocked in ``read``, which then raises LinkError.

Time: ``link.clock`` is the clock host code should use. It is the wall clock for real links and the
simulated clock for in-process lockstep links (where ``clock.sleep`` advances the simulated device),
so host code written against ``link.clock`` runs unchanged in both.
"""

from __future__ import annotations

import abc
import time
from types import TracebackType
from typing import Protocol, Self, runtime_checkable

from omnibot.errors import LinkError

__all__ = ["Clock", "Link", "WallClock", "bit_time"]

BITS_PER_BYTE = 10
"""A UART byte in 8N1 framing: start bit, 8 data bits, stop bit."""


def bit_time(baud: int) -> float:
    """Seconds one 8N1 byte takes on the line at ``baud`` (0 = unpaced, returns 0.0)."""
    if baud < 0:
        raise ValueError(f"baud must be >= 0, got {baud}")
    return BITS_PER_BYTE / baud if baud else 0.0


@runtime_checkable
class Clock(Protocol):
    """What host code may ask of time: ``now()`` in seconds and ``sleep(seconds)``."""

    def now(self) -> float:
        """Seconds on this clock (monotonic; the origin is arbitrary)."""
        ...

    def sleep(self, seconds: float) -> None:
        """Let ``seconds`` of this clock's time pass."""
        ...


class WallClock:
    """The real clock: :func:`time.monotonic` and :func:`time.sleep`."""

    def now(self) -> float:
        """The host's monotonic time, s."""
        return time.monotonic()

    def sleep(self, seconds: float) -> None:
        """Sleep ``seconds`` of wall time (nothing when <= 0)."""
        if seconds > 0:
            time.sleep(seconds)

    def __repr__(self) -> str:
        return "WallClock()"


class Link(abc.ABC):
    """A bidirectional byte stream chosen by URL (see :mod:`omnibot.transport.url`).

    Subclasses implement :meth:`_write`, :meth:`_read` and :meth:`_close`; this class checks
    arguments and the closed state, so the subclass methods only run on an open link with sane
    arguments.
    """

    baud: int = 0
    """The line's rate in bits per second (8N1) where it is paced by one (a serial port, the
    emulated line of a lockstep link); 0 where nothing paces it (TCP)."""

    def __init__(self, url: str, clock: Clock | None = None) -> None:
        self._url = url
        self._clock: Clock = clock if clock is not None else WallClock()
        self._closed = False

    # -- public API ----------------------------------------------------------------------------

    @property
    def url(self) -> str:
        """The URL this link stands for (as it would be given to ``open_link``)."""
        return self._url

    @property
    def clock(self) -> Clock:
        """The clock host code should use with this link (wall or simulated)."""
        return self._clock

    @property
    def wall_clock(self) -> bool:
        """Its :attr:`clock` is the host's :class:`WallClock` (a serial port, TCP, a pty): time runs
        on while nobody reads the link. False for a simulated link's clock (``sim://``: time moves
        only while the link is read); a wrapper (``faults+``) answers for the link it wraps."""
        return isinstance(self.clock, WallClock)

    @property
    def closed(self) -> bool:
        """True once :meth:`close` has been called."""
        return self._closed

    def line_time(self, size: int) -> float:
        """Seconds the line needs to carry ``size`` bytes one way (0.0 when it is not paced by a baud
        rate). A reply cannot start before its command has arrived, so a caller waiting for one
        adds this to its wait: a long line is not given up on while it is still being sent."""
        return size * bit_time(self.baud)

    def write(self, data: bytes) -> None:
        """Send all of ``data``. Raises LinkError if the link is closed or broken."""
        self._check_open()
        if not isinstance(data, bytes | bytearray | memoryview):
            raise TypeError(f"write() takes bytes, not {type(data).__name__}")
        if data:
            self._write(bytes(data))

    def read(self, max_bytes: int = 4096, timeout: float | None = None) -> bytes:
        """Return 1..max_bytes available bytes, waiting up to ``timeout`` s; ``b""`` on timeout."""
        return self.read_gathered(b"", 0, max_bytes, timeout)

    def read_gathered(
        self, ends: bytes, most: int, max_bytes: int = 4096, timeout: float | None = None
    ) -> bytes:
        """:meth:`read` for a reader that can act only once a byte of ``ends`` has come or more than
        ``most`` bytes have (a line decoder: a line's end, or a line too long). A link whose bytes
        come when they come returns as :meth:`read` does; one that can hold them back for nothing
        (a lockstep link, whose time moves only while it is read) may return later, at the first of
        those or the timeout, with every byte that has come by then: the reader gets the same bytes
        by the same time in fewer reads. ``ends=b""``, ``most=0``: :meth:`read`."""
        self._check_open()
        if max_bytes < 1:
            raise ValueError(f"max_bytes must be >= 1, got {max_bytes}")
        if timeout is not None and timeout < 0:
            raise ValueError(f"timeout must be >= 0 or None, got {timeout}")
        try:
            data = (
                self._read_gathered(max_bytes, timeout, ends, most)
                if ends or most
                else self._read(max_bytes, timeout)
            )
        except Exception as exc:
            if self._closed:  # closed by another thread while we were reading
                raise LinkError(f"link {self._url} was closed during read") from exc
            raise
        if self._closed:
            raise LinkError(f"link {self._url} was closed during read")
        return data

    def reopen(self, retry: float | None = None) -> None:
        """Open the underlying port or connection again after a LinkError, retrying for ``retry`` s.

        Links that cannot break (lockstep) or cannot be reopened raise LinkError.
        """
        self._check_open()
        raise LinkError(f"{self._url} cannot be reopened")

    def close(self) -> None:
        """Release the link; idempotent. Reads and writes afterwards raise LinkError."""
        if not self._closed:
            self._closed = True
            self._close()

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self._closed else "open"
        return f"<{type(self).__name__} {self._url!r} {state}>"

    # -- for subclasses ------------------------------------------------------------------------

    def _check_open(self) -> None:
        if self._closed:
            raise LinkError(f"link {self._url} is closed")

    @abc.abstractmethod
    def _write(self, data: bytes) -> None:
        """Send non-empty ``data`` on an open link."""

    @abc.abstractmethod
    def _read(self, max_bytes: int, timeout: float | None) -> bytes:
        """Read with the semantics of :meth:`read`; arguments already checked."""

    def _read_gathered(self, max_bytes: int, timeout: float | None, ends: bytes, most: int) -> bytes:
        """:meth:`read_gathered` on an open link; by default :meth:`_read` (the bytes as they come)."""
        return self._read(max_bytes, timeout)

    @abc.abstractmethod
    def _close(self) -> None:
        """Release resources; called once."""
