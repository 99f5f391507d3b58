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

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

from omnibot.control import Path, PathRecorder
from omnibot.errors import ConfigError
from omnibot.estimation import make_estimator
from omnibot.motion import Twist
from omnibot.robot import RobotDescription
from omnibot.runtime.cycle import Cycle, Notice

if TYPE_CHECKING:
    from omnibot.runtime.runtime import Runtime


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


def describe_twist(twist: Twist) -> str:
    """A twist for a status line: speed (m/s), direction of travel (deg, body frame) and turn rate."""
    speed = math.hypot(twist.vx, twist.vy)
    course = f" at {round(math.degrees(math.atan2(twist.vy, twist.vx))) + 0:+d} deg" if speed >= 0.005 else ""
    return f"{speed:.2f} m/s{course}, {round(twist.w, 2) + 0.0:+.2f} rad/s"


class SpeedReport:
    """Every ``every`` s of the cycle clock while a source drives the robot at a steady twist: the
    twist asked and the one achieved (the estimate's), to ``say`` (``omnibot run``'s status line)."""

    def __init__(self, say: Callable[[str], object], every: float = 2.0) -> None:
        self.say = say
        self.every = every
        self._due: float | None = None

    def __call__(self, cycle: Cycle) -> None:
        """Say asked against achieved when it is due and both are known."""
        asked, achieved = cycle.decision.twist, cycle.achieved
        if asked is None or asked.is_zero or achieved is None:
            self._due = None
            return
        if self._due is None:
            self._due = cycle.now + self.every  # the first report once the drive had time to settle
        elif cycle.now >= self._due:
            self._due = cycle.now + self.every
            self.say(
                f"{cycle.decision.source}: asked {describe_twist(asked)}; achieved {describe_twist(achieved)}"
            )


class EstimatorWhenMissing:
    """A sink that gives ``runtime`` the fused estimator of ``robot`` (with the runtime's floor slip)
    at its first cycle, unless a front end installed its own by then (a teach, a follow): odometry
    and the achieved twist every front end shows. A robot it cannot estimate is one warning."""

    def __init__(self, runtime: Runtime, robot: RobotDescription) -> None:
        self.runtime = runtime
        self.robot = robot
        self.tried = False

    @classmethod
    def add(cls, runtime: Runtime, robot: RobotDescription) -> None:
        """Add one to ``runtime`` unless a front end of the same process already did (``run``
        composes the dashboard's link, ROS 2's bridge and its own status lines on one runtime)."""
        if not any(isinstance(sink, cls) for sink in runtime.sinks):
            runtime.add_sink(cls(runtime, robot))

    def __call__(self, cycle: Cycle) -> None:
        """Install the estimator once, at the first cycle."""
        runtime = self.runtime
        if self.tried or runtime.estimator is not None:
            return
        self.tried = True
        slip = runtime.slip.params if runtime.slip is not None else None
        try:
            runtime.estimator = make_estimator("fused", self.robot, None, slip)
        except ConfigError as exc:
            runtime.notify("warn", f"no odometry: {exc}")


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
