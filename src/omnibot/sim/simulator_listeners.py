"""The simulator's listeners: each gets a :class:`~omnibot.sim.truth.Snapshot` once when added,
then after every step or every ``period`` seconds of simulated time."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from omnibot.sim.clock import SimClock
from omnibot.sim.truth import Listener, Snapshot

FloatArray = NDArray[np.float64]


@dataclass
class _ListenerSlot:
    fn: Listener
    period_us: int
    next_us: int


class Listeners:
    """:class:`~omnibot.sim.simulator.Simulator`'s listeners of its snapshots (the host calls
    :meth:`_notify` once a step when ``_next_notify_us`` is due)."""

    clock: SimClock
    _pose_row: FloatArray
    _twist_row: FloatArray
    _listeners: list[_ListenerSlot]
    _next_notify_us: int

    def snapshot(self) -> Snapshot:
        """The robot's time, pose and velocity now."""
        x, y, th = self._pose_row.tolist()
        vx, vy, w = self._twist_row.tolist()
        return Snapshot(self.clock.now(), x, y, th, vx, vy, w)

    def add_listener(self, fn: Listener, period: float | None = None) -> None:
        """Call ``fn(snapshot)`` now, then after every step (period None) or every ``period`` s."""
        period_us = 0 if period is None else max(1, round(period * 1e6))
        now = self.clock.ticks_us()
        self._listeners.append(_ListenerSlot(fn, period_us, now + period_us))
        self._next_notify_us = min(slot.next_us for slot in self._listeners)
        fn(self.snapshot())

    def remove_listener(self, fn: Listener) -> None:
        """Stop calling ``fn``."""
        self._listeners = [s for s in self._listeners if s.fn != fn]
        self._next_notify_us = min((slot.next_us for slot in self._listeners), default=0)

    def _notify(self) -> None:
        """Call the listeners that are due with one snapshot of now."""
        now = self.clock.ticks_us()
        snap: Snapshot | None = None
        for slot in self._listeners:
            if now >= slot.next_us:
                snap = snap or self.snapshot()
                if slot.period_us:
                    slot.next_us = (now // slot.period_us + 1) * slot.period_us
                slot.fn(snap)
        self._next_notify_us = min((slot.next_us for slot in self._listeners), default=0)


__all__ = ["Listeners"]
