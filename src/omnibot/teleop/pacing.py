"""Real-time pacing of a loop that owns a client, on real links and on the lockstep simulator alike.

The client pumps its link in the caller's thread, and on ``sim://`` a wait advances simulated time
as fast as the simulator steps (about 50 times faster than real time). A person at a joystick or a
web page needs the robot to live in real time, so a real-time loop waits with :meth:`Pacer.wait`::

    tick k is due at wall0 + k * period (wall clock) and link0 + k * period (link clock)
      1. client.sleep(link due - link now): on a real link this waits in wall time, pumping
         replies and events; on sim:// it steps the simulator up to the due time (fast)
      2. time.sleep(wall due - wall now): whatever wall time is left (sim:// only, in practice)

So simulated time follows the wall clock tick by tick, with no thread of its own. If a tick is
late by more than ``max_lag`` (a stalled process), the schedule restarts from now rather than
running a burst of ticks to catch up. Given the runtime's :class:`~omnibot.runtime.wakeup.Wakeup`,
both waits end early when a source raises it (the tick stays due: the next call waits on for it).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from omnibot.runtime import Wakeup


class _Pumped(Protocol):
    """What the pacer needs of a client: its link clock and a pumping sleep."""

    @property
    def clock(self) -> _Clock: ...

    def sleep(self, seconds: float) -> None: ...

    def pump(self, timeout: float = 0.0) -> int: ...


class _Clock(Protocol):
    def now(self) -> float: ...


class Pacer:
    """Ticks every ``period`` s of wall time, keeping the client's link clock in step."""

    def __init__(
        self,
        client: _Pumped,
        period: float,
        *,
        max_lag: float = 0.5,
        wall: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        if period <= 0:
            raise ValueError(f"period must be > 0 s, got {period}")
        self.client = client
        self.period = period
        self.max_lag = max_lag
        self._wall = wall
        self._sleep = sleep
        self.ticks = 0
        self.resyncs = 0
        """How often the schedule restarted because a tick was too late."""
        self._resuming = False
        self._restart()

    def _restart(self) -> None:
        self._wall0 = self._wall()
        self._link0 = self.client.clock.now()
        self._k = 0

    def now(self) -> float:
        """The wall clock the pacer keeps (input samples use it)."""
        return self._wall()

    def wait(self, wakeup: Wakeup | None = None) -> bool:
        """Wait for the next tick, pumping the client meanwhile; False when ``wakeup`` was raised
        first (the tick is still due: call again to wait on for it), True once it is due."""
        if not self._resuming:
            self._k += 1
            self.ticks += 1
        step = self._k * self.period
        if wakeup is None:
            lag = self._link0 + step - self.client.clock.now()
            if lag > 0:
                self.client.sleep(lag)
            rest = self._wall0 + step - self._wall()
            if rest > 0:
                self._sleep(rest)
        else:
            self._resuming = True
            if not wakeup.pump_until(self.client, self._link0 + step, self._wall, wakeup.slice):
                return False
            rest = self._wall0 + step - self._wall()
            if rest > 0 and wakeup.sleep(rest, self._wall):
                return False
            self._resuming = False
        if rest < -self.max_lag:
            self.resyncs += 1
            self._restart()
        return True
