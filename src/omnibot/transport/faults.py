"""Fault injection wrapper (``faults+<url>``): drops, corrupts and delays bytes, reproducibly.

Each byte passing in an affected direction draws three numbers from that direction's own
``random.Random`` (seeded from ``seed`` and the direction): drop with probability ``drop``, else
corrupt with probability ``corrupt`` (one random bit flipped), so the fate of the n-th byte depends
only on the seed and n, not on how the stream was cut into reads and writes.

Delay: bytes are held ``delay + U(0, jitter)`` seconds on the link's clock (order kept) before they
go on. Delayed writes are sent from within later ``read``/``write``/``clock.sleep`` calls; received
bytes are timed from when this wrapper reads them from the inner link, so the delay is a minimum.
Works on every link; on a lockstep link all of it happens in simulated time. Every ``read`` asks
the inner link at least once with what is left of its timeout, however small: a lockstep link then
moves on a tick, as it does for any positive wait, so a caller's wait loop always sees time advance.
"""

from __future__ import annotations

import random
from collections import deque
from dataclasses import dataclass
from typing import Literal

from omnibot.transport.base import Clock, Link

__all__ = ["FaultLink", "FaultStats"]

Direction = Literal["tx", "rx", "both"]
_EPS = 1e-9


@dataclass
class FaultStats:
    """Counts of bytes seen, dropped and corrupted in each direction."""

    tx_bytes: int = 0
    tx_dropped: int = 0
    tx_corrupted: int = 0
    rx_bytes: int = 0
    rx_dropped: int = 0
    rx_corrupted: int = 0


class _Channel:
    """One direction: the fault draws and the delay queue."""

    def __init__(self, name: str, seed: int, link: FaultLink, active: bool) -> None:
        self.name = name
        self.rng = random.Random(f"omnibot-faults:{seed}:{name}")
        self.jitter_rng = random.Random(f"omnibot-faults:{seed}:{name}:jitter")
        self.bytes = self.dropped = self.corrupted = 0
        self.link = link
        self.active = active
        self.queue: deque[tuple[float, bytes]] = deque()
        self._last_release = float("-inf")

    def mangle(self, data: bytes) -> bytes:
        self.bytes += len(data)
        if not self.active or not (self.link.drop or self.link.corrupt):
            return data
        out = bytearray()
        dropped = corrupted = 0
        rand = self.rng.random
        for byte in data:
            r_drop, r_corrupt, bit = rand(), rand(), self.rng.randrange(8)
            if r_drop < self.link.drop:
                dropped += 1
            elif r_corrupt < self.link.corrupt:
                out.append(byte ^ (1 << bit))
                corrupted += 1
            else:
                out.append(byte)
        self.dropped += dropped
        self.corrupted += corrupted
        return bytes(out)

    def push(self, now: float, data: bytes) -> None:
        if not data:
            return
        release = now
        if self.active and (self.link.delay or self.link.jitter):
            release += self.link.delay + self.link.jitter * self.jitter_rng.random()
        release = max(release, self._last_release)
        self._last_release = release
        self.queue.append((release, data))

    def next_release(self) -> float | None:
        return self.queue[0][0] if self.queue else None

    def pop_due(self, now: float, limit: int | None = None) -> bytes:
        out = bytearray()
        while self.queue and self.queue[0][0] <= now + _EPS:
            release, data = self.queue[0]
            room = len(data) if limit is None else limit - len(out)
            out += data[:room]
            if room < len(data):
                self.queue[0] = (release, data[room:])
                break
            self.queue.popleft()
        return bytes(out)


class _FaultClock:
    """The inner link's clock; ``sleep`` also sends delayed writes when they are due."""

    def __init__(self, link: FaultLink) -> None:
        self._link = link

    def now(self) -> float:
        return self._link.inner.clock.now()

    def sleep(self, seconds: float) -> None:
        inner = self._link.inner.clock
        end = inner.now() + seconds
        while True:
            self._link.pump()
            now = inner.now()
            if now >= end - _EPS:
                return
            due = self._link.tx.next_release()
            inner.sleep((end if due is None else min(due, end)) - now)


class FaultLink(Link):
    """Wraps ``inner`` and injects faults in direction ``direction`` ("tx", "rx" or "both").

    ``drop`` and ``corrupt`` are per-byte probabilities; ``delay`` and ``jitter`` are seconds.
    """

    def __init__(
        self,
        inner: Link,
        *,
        drop: float = 0.0,
        corrupt: float = 0.0,
        delay: float = 0.0,
        jitter: float = 0.0,
        seed: int = 0,
        direction: Direction = "both",
        url: str | None = None,
    ) -> None:
        for name, p in (("drop", drop), ("corrupt", corrupt)):
            if not 0.0 <= p <= 1.0:
                raise ValueError(f"{name} must be a probability in [0, 1], got {p}")
        if delay < 0 or jitter < 0:
            raise ValueError(f"delay and jitter must be >= 0, got {delay}, {jitter}")
        if direction not in ("tx", "rx", "both"):
            raise ValueError(f"direction must be 'tx', 'rx' or 'both', got {direction!r}")
        super().__init__(url or f"faults+{inner.url}", _FaultClock(self))
        self.inner = inner
        self.drop, self.corrupt, self.delay, self.jitter = drop, corrupt, delay, jitter
        self.seed = seed
        self.tx = _Channel("tx", seed, self, direction in ("tx", "both"))
        self.rx = _Channel("rx", seed, self, direction in ("rx", "both"))

    @property
    def wall_clock(self) -> bool:
        """The wrapped link's answer: this link's clock is the inner one's, which only also sends the
        delayed writes that fall due while it sleeps (reads send them too)."""
        return self.inner.wall_clock

    @property
    def stats(self) -> FaultStats:
        """Bytes seen, dropped and corrupted so far in each direction."""
        tx, rx = self.tx, self.rx
        return FaultStats(tx.bytes, tx.dropped, tx.corrupted, rx.bytes, rx.dropped, rx.corrupted)

    def pump(self) -> None:
        """Send the delayed writes that are due now."""
        due = self.tx.pop_due(self.inner.clock.now())
        if due:
            self.inner.write(due)

    def line_time(self, size: int) -> float:
        """The wrapped link's (see :meth:`Link.line_time`)."""
        return self.inner.line_time(size)

    def reopen(self, retry: float | None = None) -> None:
        """Reopen the wrapped link (LinkError if this one was closed)."""
        self._check_open()
        self.inner.reopen(retry)

    def _write(self, data: bytes) -> None:
        self.tx.push(self.inner.clock.now(), self.tx.mangle(data))
        self.pump()

    def _read(self, max_bytes: int, timeout: float | None) -> bytes:
        clock: Clock = self.inner.clock
        deadline = None if timeout is None else clock.now() + timeout
        asked = False  # the inner link has been read once: a wait of any length then ends
        while True:
            self.pump()
            now = clock.now()
            data = self.rx.pop_due(now, max_bytes)
            if data:
                return data
            if asked and deadline is not None and now >= deadline - _EPS:
                return b""
            times = [t for t in (deadline, self.tx.next_release(), self.rx.next_release()) if t is not None]
            wait = max(0.0, min(times) - now) if times else None
            got = self.inner.read(max_bytes, wait)
            asked = True
            if got:
                self.rx.push(clock.now(), self.rx.mangle(got))

    def _close(self) -> None:
        self.tx.queue.clear()
        self.rx.queue.clear()
        self.inner.close()
