"""Clocks: one protocol, a simulated clock advanced only by its owner, and the wall clock.

Code that needs the time (firmware, sensors, recorders) takes a :class:`Clock` and never reads
``time`` itself, so the same code runs in real time or in lockstep with the simulator. There is no
module-level clock: every simulator owns its :class:`SimClock`.

The simulated clock counts whole microseconds (an ``int``), so time never drifts however many
steps are taken; ``now()`` is that count in seconds.
"""

from __future__ import annotations

import time
from typing import Protocol, runtime_checkable


@runtime_checkable
class Clock(Protocol):
    """Monotonic time source."""

    def now(self) -> float:
        """Seconds since the clock's origin."""
        ...

    def ticks_us(self) -> int:
        """Whole microseconds since the clock's origin (MicroPython's ``time.ticks_us`` without wrap)."""
        ...


class SimClock:
    """Simulated time; only the simulator that owns it calls :meth:`advance`."""

    def __init__(self, start_us: int = 0) -> None:
        if start_us < 0:
            raise ValueError(f"start_us must be >= 0, got {start_us}")
        self._us = int(start_us)

    def now(self) -> float:
        """Simulated time, s."""
        return self._us / 1_000_000

    def ticks_us(self) -> int:
        """Simulated time in whole microseconds."""
        return self._us

    def advance_us(self, us: int) -> None:
        """Move time forward by ``us`` microseconds (never backwards)."""
        if us < 0:
            raise ValueError(f"a clock cannot go backwards (advance by {us} us)")
        self._us += int(us)

    def advance(self, seconds: float) -> None:
        """Move time forward by ``seconds``, rounded to the nearest microsecond."""
        self.advance_us(round(seconds * 1e6))

    def __repr__(self) -> str:
        return f"SimClock(t={self.now():.6f} s)"


class WallClock:
    """Real time from ``time.monotonic_ns``, counted from when the clock was made."""

    def __init__(self) -> None:
        self._origin_ns = time.monotonic_ns()

    def now(self) -> float:
        """Seconds since this clock was made (monotonic)."""
        return (time.monotonic_ns() - self._origin_ns) * 1e-9

    def ticks_us(self) -> int:
        """Microseconds since this clock was made (monotonic)."""
        return (time.monotonic_ns() - self._origin_ns) // 1000

    def __repr__(self) -> str:
        return f"WallClock(t={self.now():.6f} s)"
