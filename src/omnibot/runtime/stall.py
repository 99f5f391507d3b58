"""The stall watch: the runtime stops the robot when its wheels turn while its body does not.

:class:`StallWatch` feeds every telemetry sample, the twist each cycle sent and, where a simulator
is behind the link, its truth (``truth``: the front end that knows of a simulator hands it in) to a
:class:`~omnibot.estimation.stall.StallDetector` (the gyro, the tracking wheels, the sonars and the
wheels' effort witness the body's motion on a real robot too).
On a stall, in the cycle's sinks:

* an error :class:`~omnibot.runtime.cycle.Notice` to every front end, concerning the source in
  control: a follower, a ROS 2 path or a script ends at its next cycle with the words as its
  failure (:func:`~omnibot.runtime.sources.must_end`, as a refused command ends it); a person (pad,
  page, cmd_vel) is told and drives again with a fresh command;
* ``STOP`` (unless the controller latched its emergency stop: STOP would release it).

It looks for the next stall once the evidence has ended. The detector reads the sonars only while
they measure: :func:`start_sonars` (``run``, the dashboard and ROS 2 start them).
"""

from __future__ import annotations

from typing import Protocol

from omnibot.client import RobotClient, Telemetry
from omnibot.errors import ControllerError, LinkError
from omnibot.estimation import Stall, StallDetector
from omnibot.motion import Pose2D
from omnibot.robot import RobotDescription
from omnibot.runtime.cycle import Cycle
from omnibot.runtime.runtime import Runtime

SONAR_PERIOD = 0.1
"""s between a sonar's pings (their readings ride in TEL)."""


def start_sonars(client: RobotClient, robot: RobotDescription, period: float = SONAR_PERIOD) -> None:
    """Have the controller ping every sonar of ``robot`` each ``period`` s (no stop threshold)."""
    for number in range(1, len(robot.sonars) + 1):
        client.sonar(number, period)


class Truth(Protocol):
    """Where the body truly is: a simulator's ground truth (``omnibot.transport.find_simulator``'s
    Simulator)."""

    @property
    def pose(self) -> Pose2D:
        """The body's true pose now."""
        ...


class StallWatch:
    """Watches ``runtime`` for stalls (see the module docstring); ``truth``: the simulator behind the
    link, one more witness (None: the robot's own witnesses only, as on a real robot)."""

    def __init__(self, runtime: Runtime, robot: RobotDescription, *, truth: Truth | None = None) -> None:
        self.runtime = runtime
        self.detector = StallDetector(robot)
        self.sim = truth
        self.stalls: list[Stall] = []
        """Every stall found so far."""
        self._found: list[Stall] = []
        runtime.telemetry_hooks.append(self._sample)
        runtime.add_sink(self)

    @classmethod
    def of(cls, runtime: Runtime) -> StallWatch | None:
        """The watch a front end added to ``runtime`` (None: none watches it)."""
        return next((sink for sink in runtime.sinks if isinstance(sink, cls)), None)

    @classmethod
    def on(cls, runtime: Runtime, robot: RobotDescription, *, truth: Truth | None = None) -> StallWatch:
        """The watch of ``runtime``: the one a front end already added, else a new one (``truth``:
        as the class takes it)."""
        return cls.of(runtime) or cls(runtime, robot, truth=truth)

    def close(self) -> None:
        """Stop watching (idempotent)."""
        if self._sample in self.runtime.telemetry_hooks:
            self.runtime.telemetry_hooks.remove(self._sample)
        self.runtime.remove_sink(self)

    def _sample(self, event: Telemetry) -> None:
        found = self.detector.update(event, self.sim.pose if self.sim is not None else None)
        if found is not None:
            self._found.append(found)

    def __call__(self, cycle: Cycle) -> None:
        """Hand the detector the twist sent; act on the stalls found since the last cycle."""
        self.detector.command(cycle.t, cycle.sent)
        found, self._found = self._found, []
        for stall in found:
            self.stalls.append(stall)
            runtime = self.runtime
            runtime.notify("error", stall.text, cycle.decision.source)
            client = runtime.client
            if runtime.latched or client.link.closed:
                continue
            try:
                client.stop()
            except (ControllerError, LinkError) as exc:
                runtime.notify("error", f"STOP after the stall failed: {exc}")
