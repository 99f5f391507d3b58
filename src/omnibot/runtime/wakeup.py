"""Waking the runtime between cycles: a source that hears of a command pushes it in at once.

A source that learns of a command in a thread of its own (a DDS listener: ROS 2's ``cmd_vel``) must
not touch the client, which the runtime's loop owns. It calls the wake function the runtime handed
it (:meth:`Runtime.add_source <omnibot.runtime.runtime.Runtime.add_source>` gives one to every
source with a ``wake_with(wake)`` method). The loop's wait (:meth:`LinkPacer.wait
<omnibot.runtime.pacing.LinkPacer.wait>`, teleop's :class:`~omnibot.teleop.pacing.Pacer`) then
ends early and the runtime *reacts* (:meth:`Runtime.react
<omnibot.runtime.runtime.Runtime.react>`): it asks the woken sources only, arbitrates (a person's pad
or deadman, an emergency stop still win) and sends through its one send site; then it waits on for
the cycle that was due, whose schedule is unchanged::

    DDS thread:   sample arrives -> listener -> wake("ros2")      (sets a flag; nothing else)
    loop thread:  ... wait(wakeup) -- woken --> react(): propose, arbitrate, send ... wait(wakeup)

The wait looks at the flag between reads of the link, each at most :data:`SLICE` of the link's
clock long when the loop keeps to the wall clock (a real link, or teleop's pacer on ``sim://``, which
steps the simulator ahead to the tick), and while the pacer sleeps off wall time at once (a
:class:`threading.Event`). Reactions are at least :data:`GAP` apart on the pacer's clock (a flood
of commands cannot crowd the link): a wake sooner is taken by the reaction at the end of the gap, or
by the cycle when that comes first, so no command is lost that a newer one has not replaced. A cycle
takes the wakes raised before it (its sources' proposals take what had arrived).

**Lockstep** (``sim://`` under :class:`~omnibot.runtime.pacing.LinkPacer`): time is the simulator's
and moves only while the loop waits on the link. There the flag is looked at after every read of
the link, whatever it returned (a reply, telemetry, the read's timeout), and never in between, so
an event is taken at the simulated instant of the read that followed it. A wake raised by what the
simulation itself delivers (a telemetry listener, a scripted feed on the link clock) is taken at the
same simulated instant on every run: the run stays deterministic for its seed. A wake raised from
another thread (DDS) is taken at the next read: such a run is as reproducible as the arrival of its
commands. Lockstep reads are not sliced (they are those the loop made before: without any wake, a
run is the one it was before, bit for bit).
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import Protocol

SLICE = 0.001
"""s: the longest read of a link on the wall clock while a wake may come (a wake's latency bound)."""
GAP = 0.005
"""s of the pacer's clock between two reactions (at most 200 event-driven VELs a second)."""

Wake = Callable[[], None]
"""A source's wake function: safe to call from any thread, any number of times."""


class _Pumped(Protocol):
    """What the wait needs of a client: its link clock and one read of the link."""

    @property
    def clock(self) -> _Clock: ...

    def pump(self, timeout: float = 0.0) -> int: ...


class _Clock(Protocol):
    def now(self) -> float: ...


class Wakeup:
    """The flag sources raise (any thread) and the loop waits on (its own thread).

    :attr:`hold_until` is the pacer-clock time before which a raised flag does not end a wait
    (:data:`GAP` after a reaction)."""

    def __init__(self) -> None:
        self.slice = SLICE
        """s: the longest read of the link on a loop kept to the wall clock."""
        self.hold_until = -math.inf
        self._lock = threading.Lock()
        self._event = threading.Event()
        self._names: set[str] = set()
        self.wakes = 0
        """Wakes raised so far (a source may raise several before one reaction)."""

    def waker(self, name: str) -> Wake:
        """The wake function of the source ``name``."""

        def wake() -> None:
            self.wake(name)

        return wake

    def wake(self, name: str) -> None:
        """Raise the flag for the source ``name`` (any thread)."""
        with self._lock:
            self._names.add(name)
            self.wakes += 1
            self._event.set()

    def take(self) -> set[str]:
        """The sources that woke the loop since the last call; lowers the flag."""
        with self._lock:
            names, self._names = self._names, set()
            self._event.clear()
        return names

    @property
    def raised(self) -> bool:
        """A source woke the loop and no reaction has taken it yet."""
        return self._event.is_set()

    def ready(self, now: float) -> bool:
        """The flag is raised and its hold is over (``now`` on the pacer's clock)."""
        return self._event.is_set() and now >= self.hold_until

    def pump_until(
        self, client: _Pumped, deadline: float, now: Callable[[], float], slice: float = math.inf
    ) -> bool:
        """Read ``client``'s link until its clock reaches ``deadline`` (True) or the flag is
        :meth:`ready` on the pacer's clock ``now`` (False), each read at most ``slice`` s long."""
        while (remaining := deadline - client.clock.now()) > 0:
            if self.ready(now()):
                return False
            client.pump(min(remaining, slice))
        return True

    def sleep(self, seconds: float, now: Callable[[], float]) -> bool:
        """Sleep up to ``seconds`` of the wall clock ``now``; True when the flag ended it first."""
        end = now() + seconds
        while (left := end - now()) > 0:
            if self.ready(now()):
                return True
            hold = self.hold_until - now()
            if self._event.is_set() and hold > 0:
                time.sleep(min(hold, left))  # raised, but within the gap: sleep the gap off
            else:
                self._event.wait(left)
        return self.ready(now())
