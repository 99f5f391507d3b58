"""What the runtime's concerns share: :class:`RuntimeCore`, its counts, hooks, notices and the latch.

:class:`~omnibot.runtime.runtime.Runtime` is built on it with one mixin per concern:
:mod:`~omnibot.runtime.listening` (what the controller tells: telemetry, events) and
:mod:`~omnibot.runtime.sending` (the VELs the cycles send, their replies); the runtime module itself
holds the composition and the cycle. The controller's latched stop (its sonar's emergency stop, or
the battery's) is told once to every front end (:meth:`RuntimeCore._latch`), whoever saw it first.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

from omnibot.client import RobotClient, Telemetry
from omnibot.motion import Twist
from omnibot.runtime.cycle import Level, Notice

log = logging.getLogger("omnibot.runtime")
log.addHandler(logging.NullHandler())  # a library's log: shown where the application configures logging
# (front ends get every notice themselves; without this Python would print warnings twice on stderr)

LATCHED_TEXT = "emergency stop latched by the controller (sonar): let go and press again to release"
BATTERY_LATCHED_TEXT = (
    "battery stop latched by the controller: the battery is flat (below its stop threshold); charge or swap "
    "it: STOP releases the stop only once the voltage is back up"
)


@dataclass
class Counters:
    """What the runtime sent: VELs with motion, zero VELs, commands that failed."""

    vel: int = 0
    zero: int = 0
    errors: int = 0


class RuntimeCore:
    """The runtime's client, what it did and was told so far, and who hears of it."""

    client: RobotClient
    _notices: list[Notice]

    def _init_counts(self) -> None:
        """What the runtime did and the controller said so far: nothing yet."""
        self._wakers: set[str] = set()
        self.reactions = 0
        """Reactions to a woken source so far (:meth:`Runtime.react <omnibot.runtime.runtime.Runtime.react>`)."""
        self.sent = Counters()
        self.latched = False
        self._battery: float | None = None
        self.latch_reason = ""
        """Why the controller latched its stop: ``sonar`` or ``battery`` ("" while not latched)."""
        self.state: int | None = None
        """The controller's state from its telemetry (codes.STATE_*), None until one carries it."""
        self.last_twist: Twist | None = None
        self.cycles = 0
        self.samples = 0
        """Telemetry samples received so far."""
        self.rtt: float | None = None
        """Round trip of the last VEL whose reply was awaited, s (link clock)."""

    def _init_hooks(self) -> None:
        """The observers of telemetry, failed commands and notices: none yet."""
        self.telemetry_hooks: list[Callable[[Telemetry], object]] = []
        """More consumers of each telemetry sample, called right after the estimator (observers)."""
        self.error_hooks: list[Callable[[str, BaseException], object]] = []
        """Called with (source, exception) when a command fails (after the notice)."""
        self.notice_hooks: list[Callable[[Notice], object]] = []
        """Called at once with every notice, in the thread that gives it (a command's own report:
        sinks get notices only with a cycle, and a robot pushed by hand runs none)."""

    def notify(self, level: Level, text: str, source: str = "") -> None:
        """Tell every front end (sinks get it with the next cycle; the log at once)."""
        notice = Notice(level, text, source)
        self._notices.append(notice)
        for hook in self.notice_hooks:
            hook(notice)
        log.log({"info": logging.INFO, "warn": logging.WARNING}.get(level, logging.ERROR), "%s", text)

    def _latch(self, reason: str = "sonar") -> None:
        if not self.latched or self.latch_reason != reason:
            self.latched = True
            self.latch_reason = reason
            self.notify("warn", BATTERY_LATCHED_TEXT if reason == "battery" else LATCHED_TEXT)
