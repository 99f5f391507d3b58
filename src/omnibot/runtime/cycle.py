"""What one cycle of the runtime saw and did: the record every sink and source is handed."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from omnibot.client import Event, Telemetry
from omnibot.motion import Estimate, Twist
from omnibot.scan import Scan

Level = Literal["info", "warn", "error"]


@dataclass(frozen=True)
class Notice:
    """Something every front end must be told (a refused command, a latched emergency stop, a change
    of the source in control); ``source`` names the command source it concerns ("" for none)."""

    level: Level
    text: str
    source: str = ""
    kind: str = ""
    """``"control"`` for a change of the source in control (logs and the page show them; a CLI's
    status lines need not)."""


@dataclass(frozen=True)
class Decision:
    """The arbiter's verdict for a cycle: who drives (``source``, "" for nobody), what it asked for
    (``twist``, None: nothing to send) and why, in words for status lines, the page and logs."""

    source: str
    twist: Twist | None
    reason: str
    lock: str = ""
    """The lock that holds the robot ("" for none)."""
    estop: bool = False
    """That lock is an emergency stop (priority 255): whatever ran is over, not paused."""


NOBODY = Decision("", None, "no source active")


@dataclass
class Cycle:
    """One cycle: times, the state, what arrived since the last cycle, the decision, what was sent.

    ``now`` is the clock sources and timeouts use (the wall clock when a person is in the loop and
    the simulator is paced to it, else the link clock); ``t`` is the link clock, the estimate's.
    Sources are handed the cycle before :attr:`decision` is made (it still holds the previous
    cycle's); sinks get it complete.
    """

    index: int
    now: float
    t: float
    estimate: Estimate | None
    """The estimator's state predicted to ``t`` (None without an estimator or before telemetry)."""
    telemetry: list[Telemetry] = field(default_factory=list)
    events: list[Event] = field(default_factory=list)
    """Every other event since the last cycle (WARN, ERROR, RANGE, IDLE, RESET...)."""
    decision: Decision = NOBODY
    sent: Twist | None = None
    """The twist sent with VEL this cycle (clamped to the controller's limits, and with the floor's
    wheel slip asked on top when the runtime has it; None: nothing sent). What was asked for is
    :attr:`decision`'s ``twist``."""
    notices: list[Notice] = field(default_factory=list)
    latched: bool = False
    """The controller holds a latched stop: it refuses motion until STOP (:attr:`latch_reason`)."""
    latch_reason: str = ""
    """Why: ``sonar`` (the emergency stop, WARN 13) or ``battery`` (the battery stop, WARN 43: STOP
    releases it only with the voltage back up)."""
    scans: list[Scan] = field(default_factory=list)
    """The revolutions the runtime's :attr:`~omnibot.runtime.runtime.Runtime.scanner` completed since
    the last cycle, oldest first (stamped on the link clock; empty without a scanner)."""

    @property
    def achieved(self) -> Twist | None:
        """The body twist the robot achieves as estimated (None without an estimate), to set beside
        the one asked for (:attr:`decision`'s ``twist``)."""
        return None if self.estimate is None else self.estimate.body_twist
