"""The standstill before an autonomous run: a lock that holds the robot still while the gyro's bias
is learned.

The fused estimators learn the gyro's bias while the wheels do not turn; ``omnibot follow`` stands
still :data:`~omnibot.navigation.runner.STANDSTILL` s before it drives for that. On a runtime that
other front ends share (``omnibot run --follow``, with or without the dashboard) the same wait is a
lock: :class:`Standstill` masks the sources up to its priority (the follower's) from the first
cycle until ``seconds`` of the link clock have passed since the first telemetry sample, so the
follower starts on a learned bias. The page, a pad or ROS 2 (higher priorities) are not held: a
person may drive meanwhile (and then spoils the standstill, as pushing the robot would).
"""

from __future__ import annotations

from omnibot.client import Telemetry
from omnibot.runtime.arbiter import Lock
from omnibot.runtime.runtime import Runtime


class Standstill:
    """Holds the sources of ``runtime`` up to ``priority`` still for ``seconds`` of telemetry."""

    def __init__(self, runtime: Runtime, seconds: float, priority: int, *, name: str = "standstill") -> None:
        if not seconds >= 0:
            raise ValueError(f"a standstill lasts 0 s or more, got {seconds}")
        self.runtime = runtime
        self.seconds = seconds
        self.until: float | None = None
        """Link-clock time the standstill ends (None until the first telemetry sample)."""
        self.over = False
        self.lock = Lock(name, priority, self._engaged)
        runtime.telemetry_hooks.append(self._first_sample)
        runtime.add_lock(self.lock)

    def _first_sample(self, event: Telemetry) -> None:
        if self.until is None:
            self.until = event.time + self.seconds

    def _engaged(self) -> str | None:
        if self.over:
            return None
        if self.until is not None and self.runtime.client.clock.now() >= self.until:
            self.over = True
            return None
        return f"the standstill: the gyro's bias is learned ({self.seconds:g} s)"
