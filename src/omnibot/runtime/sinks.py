"""Sinks: whatever consumes each completed cycle, without a loop or a thread of its own.

A sink is any callable taking a :class:`~omnibot.runtime.cycle.Cycle`; the runtime calls every sink
once per cycle, in its own thread, after the cycle's command was sent. A sink must return quickly
(it runs inside the control loop): one that raises is logged and removed, and the robot loop goes on.

What a cycle carries: ``t`` (link clock), ``estimate`` (the state predicted to ``t``), ``telemetry``
and ``events`` (everything the controller sent since the last cycle, in order), ``decision`` (who
drives and why), ``sent`` (the twist sent) and ``notices`` (refusals, the latched emergency stop, who
took control). An adapter for a recorder fed from client listeners is a few lines::

    class McapSink:                      # e.g. the MCAP recorder of the logs branch
        def __init__(self, recorder):
            self.recorder = recorder
        def __call__(self, cycle):
            for event in (*cycle.telemetry, *cycle.events):
                self.recorder.on_event(event)   # what its client listener was given
            if cycle.estimate is not None:
                self.recorder.on_state(cycle.t, cycle.estimate)

A ROS 2 publisher is the same shape (publish ``cycle.estimate`` as odometry, the decision as a
status string); it must not block (hand messages to its executor's queue).
"""

from __future__ import annotations

from collections.abc import Callable

from omnibot.control.paths.path import Path
from omnibot.control.paths.teach import PathRecorder
from omnibot.runtime.cycle import Cycle, Notice


class NoticePrinter:
    """Passes each notice to ``say`` (a CLI front end's status lines); changes of control too when
    ``control`` is set."""

    def __init__(self, say: Callable[[str], object], *, control: bool = False) -> None:
        self.say = say
        self.control = control
        self.seen: list[Notice] = []

    def __call__(self, cycle: Cycle) -> None:
        """Say every notice of the cycle (changes of control only with ``control``)."""
        for notice in cycle.notices:
            self.seen.append(notice)
            if notice.kind != "control" or self.control:
                self.say(notice.text)


class TeachSink:
    """Teach: records the estimated path while the robot is driven (by any source) or pushed."""

    def __init__(self, recorder: PathRecorder | None = None) -> None:
        self.recorder = recorder or PathRecorder("distance", 0.02)

    def __call__(self, cycle: Cycle) -> None:
        """Offer the cycle's estimated pose to the recorder."""
        e = cycle.estimate
        if e is not None:
            self.recorder.add(e.t, e.x, e.y, e.theta)

    def path(self) -> Path:
        """The path recorded so far."""
        return self.recorder.path()


class Trace:
    """Plots and reports: the time, the estimate and the twist sent at every cycle that sent one."""

    def __init__(self, source: str | None = None) -> None:
        self.source = source
        """Only cycles this source drove (None: every cycle that sent a twist)."""
        self.t: list[float] = []
        self.estimate: list[tuple[float, float, float]] = []
        self.command: list[tuple[float, float, float]] = []

    def __call__(self, cycle: Cycle) -> None:
        """Record the cycle if it sent a twist (from ``source``, when given)."""
        if cycle.sent is None or cycle.estimate is None:
            return
        if self.source is not None and cycle.decision.source != self.source:
            return
        e = cycle.estimate
        self.t.append(cycle.t)
        self.estimate.append((e.x, e.y, e.theta))
        self.command.append(tuple(cycle.sent))  # type: ignore[arg-type]
