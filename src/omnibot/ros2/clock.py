"""The time the bridge stamps with, and ``/clock`` for a simulator.

One clock per robot link, placed once on the wall clock (:class:`Timeline`), never re-placed:

* a real robot: the link's clock is the host's monotonic clock, so a stamp is the wall clock of the
  moment the data was handled (the offset fixed at the start: a step of the system clock, NTP's, does
  not make stamps jump);
* a simulator (``sim://``): the simulation's time. It stops when the host stalls (the bridge stopped,
  swapped out) and goes on from there, so after a stall it is behind the wall clock for good: a node
  comparing stamps with its wall clock would see every later message as old. The bridge therefore
  publishes ``/clock`` (rosgraph_msgs/Clock, :data:`CLOCK`) with the simulated time each cycle,
  before anything stamped in that cycle, and a node with ``use_sim_time`` true follows it, paced
  or lockstep, stall or not.

Several robots of one process share one :class:`Timeline`: one origin, and a ``/clock`` that never
goes backwards whichever robot's cycle publishes it.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

CLOCK = "/clock"
CLOCK_TYPE = "rosgraph_msgs/msg/Clock"


class Timeline:
    """A process's placing of link time on the wall clock, and the newest ``/clock`` published."""

    def __init__(self, wall_ns: Callable[[], int] = time.time_ns) -> None:
        self._wall_ns = wall_ns
        self._origin: tuple[float, int] | None = None
        self._lock = threading.Lock()
        self.clock_ns = -1
        """The newest time put on ``/clock`` (-1: none yet)."""

    def origin(self, t: float) -> tuple[float, int]:
        """(link time, ns since the epoch) of one instant: the first caller's ``t`` and the wall
        clock when it asked; every later caller gets the same."""
        with self._lock:
            if self._origin is None:
                self._origin = (t, self._wall_ns())
            return self._origin

    def adopt(self, placing: tuple[float, int] | None) -> None:
        """Place link time as ``placing`` (link time, ns since the epoch) does: the command's log's,
        so the bridge's stamps are the log's (unless an origin is already given out)."""
        with self._lock:
            if self._origin is None and placing is not None:
                self._origin = placing

    def advance(self, ns: int) -> bool:
        """True when ``ns`` is later than every ``/clock`` so far (it becomes the newest)."""
        with self._lock:
            if ns <= self.clock_ns:
                return False
            self.clock_ns = ns
            return True
