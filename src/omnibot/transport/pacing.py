"""Hold a byte stream to a UART's rate in wall-clock time: a token bucket, 10 bits per byte.

A pseudo-terminal moves bytes as fast as the kernel can; a real 8N1 UART at 115200 baud moves 11520
bytes/s. The pty emulator asks a :class:`Pacer` how many bytes it may pass on now::

    tokens += (now - last) * baud / 10, capped at ``burst``    (bytes allowed, fractional)
    send n <= floor(tokens) bytes; tokens -= n

``burst`` is the number of bytes that may go back to back after an idle spell (a UART's FIFO depth);
keep it small so the long-run rate is the baud rate from the first byte on.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

from omnibot.transport.base import bit_time

__all__ = ["Pacer"]


class Pacer:
    """Token bucket: ``take(n)`` grants up to ``n`` bytes now; ``delay(n)`` says how long to wait.

    ``baud=0`` means unpaced: every request is granted at once.
    """

    def __init__(self, baud: int, *, burst: int = 16, clock: Callable[[], float] = time.monotonic) -> None:
        if burst < 1:
            raise ValueError(f"burst must be >= 1 byte, got {burst}")
        self.byte_time = bit_time(baud)
        self.baud = baud
        self.burst = burst
        self._clock = clock
        self._tokens = float(burst)
        self._last = clock()

    def _refill(self) -> None:
        now = self._clock()
        if self.byte_time:
            self._tokens = min(float(self.burst), self._tokens + (now - self._last) / self.byte_time)
        self._last = now

    def available(self) -> int:
        """Bytes that may be sent now."""
        if not self.byte_time:
            return 2**62
        self._refill()
        return math.floor(self._tokens + 1e-9)

    def take(self, n: int) -> int:
        """Grant and consume up to ``n`` bytes; return how many were granted (maybe 0)."""
        if not self.byte_time:
            return n
        granted = min(n, self.available())
        self._tokens -= granted
        return granted

    def delay(self, n: int = 1) -> float:
        """Seconds until ``n`` bytes (at most ``burst``) may be taken; 0.0 if they may now."""
        if not self.byte_time:
            return 0.0
        self._refill()
        missing = min(n, self.burst) - self._tokens
        return max(0.0, missing * self.byte_time)

    def wait(self, n: int, sleep: Callable[[float], None] = time.sleep) -> None:
        """Block until ``n`` bytes have been granted (in bursts), consuming them."""
        while n > 0:
            got = self.take(n)
            n -= got
            if n:
                sleep(self.delay(min(n, self.burst)))
