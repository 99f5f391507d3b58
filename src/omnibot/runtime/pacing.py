"""Pacers: when the runtime's next cycle is due (the link clock's, or a front end's own).

:class:`Pacer` is what :class:`~omnibot.runtime.runtime.Runtime` asks; :class:`LinkPacer` its default,
on the link clock: real time on a real link, the simulator's time in lockstep on ``sim://``.
"""

from __future__ import annotations

import math
from typing import Protocol

from omnibot.client import RobotClient
from omnibot.runtime.wakeup import Wakeup


class Pacer(Protocol):
    """When cycles happen: ``now()`` is the cycle clock, ``wait()`` waits (pumping the client)."""

    def now(self) -> float:
        """The cycle clock, s."""

    def wait(self, wakeup: Wakeup | None = None) -> bool | None:
        """Wait for the next cycle, pumping the client meanwhile; with ``wakeup``, False when it
        was raised before the cycle was due (call again to wait on for the same cycle)."""


class LinkPacer:
    """Cycles every ``period`` s of the link clock: real time on a real link, simulated time (lockstep,
    deterministic) on ``sim://``. A late cycle is not made up for: the next one is due a period later."""

    def __init__(self, client: RobotClient, period: float) -> None:
        if not period > 0:
            raise ValueError(f"period must be > 0 s, got {period}")
        self.client = client
        self.period = period
        self._next = client.clock.now()
        self._resuming = False

    def now(self) -> float:
        """The link clock, s."""
        return self.client.clock.now()

    def wait(self, wakeup: Wakeup | None = None) -> bool:
        """Sleep through the client (lockstep on ``sim://``) until the next cycle is due; after a
        cycle that ran past its successor's time (a slow start, a stalled link) the schedule starts
        again from now, rather than running the missed cycles back to back. With ``wakeup``: False
        when it was raised first (the cycle is still due: the next call waits on for it)."""
        now = self.client.clock.now()
        if not self._resuming:
            self._next += self.period
            if self._next < now:
                self._next = now + self.period
        if wakeup is None:
            self.client.sleep(max(0.0, self._next - now))
            return True
        wall = self.client.link.wall_clock  # lockstep: whole reads, as without a wakeup
        self._resuming = not wakeup.pump_until(
            self.client, self._next, self.now, wakeup.slice if wall else math.inf
        )
        return not self._resuming
