"""When teleop drives and how it stops: a small pure state machine, called once per command period.

::

              enabled and fresh input
      IDLE ---------------------------> DRIVING --- each period: VEL(twist) -----+
       ^                                  |  ^                                   |
       |  after stop_repeats zero VELs    |  +-----------------------------------+
       +---------- STOPPING <-------------+  released (deadman let go), lost (pad gone:
                   each period: VEL(0)       no reading), quiet (newest reading older
                                             than input_timeout)

While driving, every period sends a VEL that holds the twist for ``vel_timeout`` (the controller's
watchdog), so a teleop that dies mid-drive stops the robot within ``vel_timeout``. When driving ends,
a single zero command can be lost (the failure users of other teleop tools report most), so
``stop_repeats`` zero VELs are sent, one per period; then teleop falls silent and the controller's
watchdog ends the last VEL (IDLE). No STOP is sent: it would also release a sonar emergency-stop
latch behind the user's back.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from omnibot.motion import ZERO, Twist


class Phase(Enum):
    """Where the deadman is (see the module diagram): idle, driving while it is held, or stopping
    (zero VELs) after driving ended."""

    IDLE = "idle"
    DRIVING = "driving"
    STOPPING = "stopping"


class Why(Enum):
    """Why driving ended."""

    RELEASED = "released"
    LOST = "lost"
    QUIET = "quiet"


@dataclass(frozen=True)
class Sample:
    """Input for one period: the limited twist asked for, whether the deadman is held, and when the
    input was read (same clock as the ``now`` given to :meth:`Deadman.update`)."""

    twist: Twist
    enabled: bool
    time: float


@dataclass(frozen=True)
class Action:
    """What to send this period: a VEL with ``twist`` or nothing (``twist`` None).

    ``started`` marks the first VEL of a drive (a fresh press of the deadman); ``ended`` says why
    driving ended on the period it did (None otherwise).
    """

    twist: Twist | None
    started: bool = False
    ended: Why | None = None


class Deadman:
    """Decides, period by period, whether to send the input's twist, a zero, or nothing."""

    def __init__(self, input_timeout: float, stop_repeats: int) -> None:
        if input_timeout <= 0 or stop_repeats < 1:
            raise ValueError(
                f"need input_timeout > 0 and stop_repeats >= 1, got {input_timeout}, {stop_repeats}"
            )
        self.input_timeout = input_timeout
        self.stop_repeats = stop_repeats
        self.phase = Phase.IDLE
        self.last_end: Why | None = None
        self._zeros_left = 0

    def update(self, now: float, sample: Sample | None) -> Action:
        """The action for this period, given the newest input (None: no input device)."""
        why = self._why_not(now, sample)
        if why is None:
            assert sample is not None
            started = self.phase is not Phase.DRIVING
            self.phase = Phase.DRIVING
            return Action(sample.twist, started=started)
        ended = None
        if self.phase is Phase.DRIVING:
            self.phase = Phase.STOPPING
            self._zeros_left = self.stop_repeats
            self.last_end = ended = why
        if self.phase is Phase.STOPPING:
            self._zeros_left -= 1
            if self._zeros_left <= 0:
                self.phase = Phase.IDLE
            return Action(ZERO, ended=ended)
        return Action(None)

    def _why_not(self, now: float, sample: Sample | None) -> Why | None:
        if sample is None:
            return Why.LOST
        if now - sample.time > self.input_timeout:
            return Why.QUIET
        if not sample.enabled:
            return Why.RELEASED
        return None

    def reset(self) -> None:
        """Forget any drive (e.g. after an emergency stop): silent until the next fresh input."""
        self.phase = Phase.IDLE
        self._zeros_left = 0
