"""In-process lockstep link: the host drives a simulated device, and time is the device's time.

There is no thread and no wall-clock wait. ``read(timeout=t)`` steps the device tick by tick until
bytes have reached the host or ``t`` seconds of *simulated* time have passed; ``clock.sleep(t)`` steps
it for ``t`` simulated seconds. So a test or benchmark runs as fast as the device can be stepped, and
the same inputs give the same bytes at the same simulated times.

The UART is modelled as two paced FIFOs in simulated time::

    host.write() --> [ tx FIFO: 10 bits/baud per byte ] --> device.receive()   (before each step)
    host.read()  <-- [ rx FIFO: 10 bits/baud per byte ] <-- device.transmit()  (after each step)

A byte leaves its FIFO when its last bit is on the other side; a byte written while the line is busy
queues behind the others, so throughput is capped at ``baud / 10`` bytes per simulated second in each
direction (``baud=0``: unpaced, bytes arrive at the next tick boundary). Simulated time moves in whole
device ticks, so waits round up to whole ticks and a positive wait always moves at least one tick.

A read returns on the tick its first bytes arrive. A paced line brings a line a few bytes a tick, so
a reader that can only act at a line's end (the client's waits) reads
:meth:`~omnibot.transport.Link.read_gathered`: the link steps on until a byte that ends a line has
arrived (or more than the reader can take without one, or the timeout), and hands over every byte
arrived by then, the bytes and times of the reads it saves. While no byte is on its way to the device
and none on the way to the host would end the wait within a tick, a device with ``run_quiet``
(:class:`QuietSteps`) takes the ticks in one call (:meth:`LockstepLink._run`); the bytes that
arrived meanwhile are taken at its end, the same as tick by tick (:meth:`PacedFifo.pop_due` is a
function of the time it is asked at).
"""

from __future__ import annotations

import math
import threading
from collections import deque
from typing import Protocol, runtime_checkable

from omnibot.errors import LinkError
from omnibot.transport.base import Link, bit_time

__all__ = ["DEFAULT_BAUD", "LockstepClock", "LockstepDevice", "LockstepLink", "PacedFifo", "QuietSteps"]

DEFAULT_BAUD = 115200
_EPS = 1e-9  # relative slack when turning a duration into whole ticks
_EDGE = 1e-6  # ticks: a time this close after a tick's end may be on it for the device's clock
_FOREVER = 1 << 62  # ticks a read without a timeout may wait (146,000 years of 1 ms ticks)


@runtime_checkable
class LockstepDevice(Protocol):
    """A device that can be stepped by the host (the simulated controller implements this).

    ``time`` is the device's simulated time in seconds and ``tick`` the seconds one :meth:`step`
    advances it by (both may be plain attributes or read-only properties). Optionally a device may
    have ``close()``; :class:`LockstepLink` calls it when the link is closed.
    """

    @property
    def time(self) -> float:
        """Simulated seconds; advanced by ``tick`` on every :meth:`step`."""
        ...

    @property
    def tick(self) -> float:
        """Seconds of simulated time per :meth:`step` (e.g. 0.001)."""
        ...

    def receive(self, data: bytes) -> None:
        """Bytes from the host, delivered to the device's UART."""
        ...

    def step(self) -> None:
        """Advance one device tick."""
        ...

    def transmit(self) -> bytes:
        """Bytes the device has sent since the last call (``b""`` if none)."""
        ...


@runtime_checkable
class QuietSteps(Protocol):
    """A :class:`LockstepDevice` that can take several ticks in one call while nothing reaches it
    (and nobody waits on what is on its way to the host)."""

    def run_quiet(self, ticks: int) -> int:
        """Step up to ``ticks`` ticks, stopping after the first one in which the device sent bytes
        (left for :meth:`LockstepDevice.transmit`); the ticks taken. The same as that many
        :meth:`LockstepDevice.step` calls, without the link's look at both lines between them."""
        ...


class PacedFifo:
    """A byte FIFO whose bytes come out no faster than one per ``byte_time`` seconds.

    ``push(now, data)`` puts bytes on the line at time ``now`` (after anything still on it);
    ``pop_due(now)`` returns the bytes whose last bit has arrived by ``now``.
    """

    def __init__(self, byte_time: float) -> None:
        self.byte_time = byte_time
        self._chunks: deque[tuple[float, bytes]] = deque()  # (start time of first byte, bytes)
        self._line_free = -math.inf
        self.pending = 0
        """Bytes on the line (``len()`` of the FIFO, as an attribute for the link's every tick)."""

    def __len__(self) -> int:
        return self.pending

    def push(self, now: float, data: bytes) -> None:
        """Put ``data`` on the line at ``now`` s, after anything still on it."""
        if not data:
            return
        start = max(now, self._line_free)
        self._chunks.append((start, data))
        self._line_free = start + len(data) * self.byte_time
        self.pending += len(data)

    def pop_due(self, now: float) -> bytes:
        """The bytes whose last bit has arrived by ``now`` s (a chunk may be split)."""
        chunks = self._chunks
        byte_time = self.byte_time
        out = b""
        while chunks:
            start, data = chunks[0]
            size = len(data)
            if byte_time == 0.0:
                n = size if start <= now else 0
            else:
                n = min(size, math.floor((now - start) / byte_time + _EPS))
            if n <= 0:
                break
            if n == size:
                out += data
                chunks.popleft()
            else:
                out += data[:n]
                chunks[0] = (start + n * byte_time, data[n:])
                break
        self.pending -= len(out)
        return out

    def arrival(self, n: int) -> float:
        """From when :meth:`pop_due` counts the ``n``-th byte on the line (1-based) as arrived, s (inf:
        fewer are on it)."""
        for start, data in self._chunks:
            if n <= len(data):
                return start + (n - _EPS) * self.byte_time
            n -= len(data)
        return math.inf

    def first_of(self, ends: bytes) -> int:
        """How many bytes on the line come before the first byte of ``ends`` (-1: none of them)."""
        before = 0
        for _, data in self._chunks:
            found = [i for i in map(data.find, ends) if i >= 0]
            if found:
                return before + min(found)
            before += len(data)
        return -1

    def clear(self) -> None:
        """Drop everything on the line."""
        self._chunks.clear()
        self.pending = 0


class LockstepClock:
    """The simulated clock of a :class:`LockstepLink`: ``now()`` is the device's time."""

    def __init__(self, link: LockstepLink) -> None:
        self._link = link

    def now(self) -> float:
        """The device's simulated time, s."""
        return self._link.device.time

    def sleep(self, seconds: float) -> None:
        """Step the device for ``seconds`` of simulated time (rounded up to whole ticks)."""
        self._link.advance(seconds)

    def __repr__(self) -> str:
        return f"LockstepClock(now={self.now():.6f})"


class LockstepLink(Link):
    """A :class:`Link` to a :class:`LockstepDevice` stepped in the caller's thread.

    Meant to be driven from one thread: every blocking call advances simulated time, so a
    background reader thread would make simulated time run as fast as it loops. Calls are
    serialised by a lock, so using it from several threads is safe, just not deterministic.
    """

    def __init__(self, device: LockstepDevice, *, baud: int = DEFAULT_BAUD, url: str | None = None) -> None:
        if device.tick <= 0:
            raise ValueError(f"device tick must be > 0 s, got {device.tick}")
        super().__init__(url or f"lockstep://{type(device).__name__}?baud={baud}")
        self._clock = LockstepClock(self)
        self.device = device
        self.baud = baud
        byte_time = bit_time(baud)
        self._to_device = PacedFifo(byte_time)
        self._to_host = PacedFifo(byte_time)
        self._inbox = bytearray()  # arrived at the host, not yet read
        self._lock = threading.RLock()
        self.steps = 0
        """Device steps taken through this link."""
        self._run_quiet = device.run_quiet if isinstance(device, QuietSteps) else None

    @property
    def in_waiting(self) -> int:
        """Bytes that have arrived at the host and not been read yet."""
        with self._lock:
            self._collect()
            return len(self._inbox)

    def advance(self, seconds: float) -> None:
        """Step the device for ``seconds`` of simulated time (whole ticks, at least one if > 0)."""
        self._check_open()
        with self._lock:
            ticks = self._ticks_for(seconds)
            while ticks > 0:  # nobody reads meanwhile: the line to the host never holds the device back
                ticks -= self._run(ticks, b"", _FOREVER)

    def _ticks_for(self, seconds: float) -> int:
        if seconds <= 0:
            return 0
        return max(1, math.ceil(seconds / self.device.tick - _EPS))

    def _run(self, ticks: int, ends: bytes = b"", most: int = 0) -> int:
        """Step at most ``ticks`` (>= 1) ticks; the ticks taken. While nothing is on the line to the
        device, the device runs until it sends (one call, the same ticks) or, with bytes on the line
        to the host, until they may be gathered (:meth:`_gathered`); else one tick at a time (a plain
        read, ``most`` 0, takes the first byte, which a busy line brings on the next tick)."""
        if self._run_quiet is None or self._to_device.pending:
            self._step()
            return 1
        if self._to_host.pending:
            ticks = min(ticks, self._ticks_ungathered(ends, most)) if most else 0
            if ticks < 1:
                self._step()
                return 1
        taken = self._run_quiet(ticks)
        self.steps += taken
        self._drain()
        return taken

    def _ticks_ungathered(self, ends: bytes, most: int) -> int:
        """Whole ticks to the one on which the first byte on the line to the host that would gather
        them arrives (a long stretch when none would): short by one if it arrives within
        :data:`_EDGE` of a tick's end (the next run takes that tick), never long."""
        line = self._to_host
        need = most + 1 - len(self._inbox)
        end = line.first_of(ends)
        if end >= 0:
            need = min(need, end + 1)
        due = line.arrival(need)
        if due == math.inf:
            return _FOREVER
        return math.ceil((due - self.device.time) / self.device.tick - _EDGE)

    def _step(self) -> None:
        self._feed()
        self.device.step()
        self.steps += 1
        self._drain()

    def _feed(self) -> None:
        """Before a tick: hand the device the bytes whose last bit has reached it."""
        if not self._to_device.pending:  # the line is idle on most ticks: no clock to read
            return
        due = self._to_device.pop_due(self.device.time)
        if due:
            self.device.receive(due)

    def _drain(self) -> None:
        """After a tick: put what the device sent on the line to the host; take what has arrived."""
        out = self.device.transmit()
        if out:
            self._to_host.push(self.device.time, out)
        if self._to_host.pending:
            self._collect()

    def _collect(self) -> None:
        if not self._to_host.pending:
            return
        arrived = self._to_host.pop_due(self.device.time)
        if arrived:
            self._inbox += arrived

    def _write(self, data: bytes) -> None:
        with self._lock:
            self._to_device.push(self.device.time, data)

    def _read_gathered(self, max_bytes: int, timeout: float | None, ends: bytes, most: int) -> bytes:
        return self._read(max_bytes, timeout, ends, most)

    def _read(self, max_bytes: int, timeout: float | None, ends: bytes = b"", most: int = 0) -> bytes:
        """Step until the bytes arrived are gathered (:meth:`_gathered`; a plain read: the first
        byte) or ``timeout`` s have passed; then up to ``max_bytes`` of them. Gathered reads come
        here too, so a test's stand-in for ``_read`` (an unplugged cable) stands in for both."""
        with self._lock:
            self._collect()
            inbox = self._inbox
            if timeout != 0 and not (inbox and self._gathered(0, ends, most)):
                ticks = _FOREVER if timeout is None else self._ticks_for(timeout)
                taken = 0
                while taken < ticks and not self._closed:
                    seen = len(inbox)
                    taken += self._run(ticks - taken, ends, most)
                    if len(inbox) > seen and (len(inbox) > most or self._gathered(seen, ends, most)):
                        break  # a plain read (most 0) at its first byte, without a call
            chunk = bytes(inbox[:max_bytes])
            del inbox[:max_bytes]
            return chunk

    def _gathered(self, since: int, ends: bytes, most: int) -> bool:
        """The inbox holds more than ``most`` bytes, or a byte of ``ends`` from ``since`` on."""
        inbox = self._inbox
        return len(inbox) > most or any(inbox.find(end, since) >= 0 for end in ends)

    def _close(self) -> None:
        with self._lock:
            self._to_device.clear()
            self._to_host.clear()
            self._inbox.clear()
            close = getattr(self.device, "close", None)
            if callable(close):
                try:
                    close()
                except Exception as exc:
                    raise LinkError(f"closing the device of {self.url} failed: {exc}") from exc
