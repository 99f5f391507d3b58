"""Periodic, non-blocking sonar ranging with RANGE bands and the emergency-stop threshold.

Each configured sonar is pinged every ``period`` ms on a fixed timeline: ``hal.sonar_start(s)``
triggers it and ``hal.sonar_read(s)`` is polled until it returns the range (cm, -1 for no echo).
A reading that meets the band is reported as ``RANGE,<sonar>,<cm>``: inside [LOW, HIGH] when
LOW < HIGH, outside [HIGH, LOW] when LOW > HIGH; no-echo readings are never reported. Whether a
reading stops the robot is the guard's business (safety.py): :meth:`Sonars.poll` says which sonars
have a new reading.
"""

SONAR_BASE = 1  # protocol number of the first sonar (HAL indices start at 0)
RANGE_MAX_CM = 500
READ_TIMEOUT_MS = 100  # a HAL that never answers counts as no echo after this


class Sonars:
    """Schedules pings and judges readings for every sonar of the robot."""

    def __init__(self, count: int) -> None:
        self.count = count
        self.period = [0] * count
        self.low = [0] * count
        self.high = [0] * count
        self.stop = [0] * count
        self.last = [-1] * count
        self._next = [0] * count
        self._pending = [False] * count
        self._started = [0] * count

    def configure(self, s: int, period: int, low: int, high: int, stop: int, now_ms: int) -> None:
        """Set sonar s (HAL index); period 0 switches it off."""
        self.period[s] = period
        self.low[s] = low
        self.high[s] = high
        self.stop[s] = stop
        self._next[s] = now_ms

    def off(self) -> None:
        """Stop every sonar measuring."""
        for s in range(self.count):
            self.period[s] = 0

    def poll(self, hal: "HAL", now_ms: int, report: "Callable[[int, int], None]") -> int:
        """Start due pings, collect readings, ``report(sonar, cm)`` those in their band.

        Returns a bit mask of the sonars (bit s for HAL index s) with a new reading in :attr:`last`.
        """
        fresh = 0
        for s in range(self.count):
            if self._pending[s]:
                cm = hal.sonar_read(s)
                if cm is None:
                    if now_ms - self._started[s] < READ_TIMEOUT_MS:
                        continue
                    cm = -1
                self._pending[s] = False
                self.last[s] = cm
                if self.period[s] == 0:
                    continue
                fresh |= 1 << s
                if cm < 0:
                    continue
                lo = self.low[s]
                hi = self.high[s]
                if (lo < hi and lo <= cm <= hi) or (lo > hi and (cm < hi or cm > lo)):
                    report(s + SONAR_BASE, cm)
            elif self.period[s] > 0 and now_ms - self._next[s] >= 0:
                self._next[s] += self.period[s]
                if now_ms - self._next[s] >= 0:
                    self._next[s] = now_ms + self.period[s]
                self._pending[s] = True
                self._started[s] = now_ms
                hal.sonar_start(s)
        return fresh


TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Callable

    from omnibot.firmware.hal import HAL
