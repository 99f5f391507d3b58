"""The calibration's runner: one command at a time (POWER, MOVE, ROTATE), measured.

Nothing here knows whether the robot is real or simulated: every run is protocol commands (POWER,
MOVE, ROTATE) and a measurement by the chosen truth strategy, so the same code calibrates a board on
a serial port and the simulator in lockstep.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Any

from omnibot.calibration.patterns import Geometry, Rate
from omnibot.calibration.runs import STRAIGHT, RunInfo, RunResult, relative
from omnibot.calibration.tap import TelemetryTap
from omnibot.calibration.truth import TruthSource
from omnibot.client import RobotClient, WarnEvent
from omnibot.progress import Progress
from omnibot.protocol import text
from omnibot.protocol.messages import Command
from omnibot.robot import MotorMapSpec, RobotDescription

STILL_TIMEOUT = 5.0
"""s the runner waits at most for the encoders to stop after a run."""


@dataclass
class Runner:
    """Runs one command at a time and measures it (see the module docstring)."""

    client: RobotClient
    robot: RobotDescription
    truth: TruthSource
    tap: TelemetryTap
    settle: float = 0.4
    progress: Progress | None = None
    motors: MotorMapSpec | None = None
    """The motor map the sweeps' patterns go through (the firmware's, mirrored; None: raw)."""
    rate: Rate | None = None
    """The rim speed a nominal power gives, for the map's speed term (the balance runs' measure)."""
    log: list[RunResult] = field(default_factory=list)
    _warns: list[int] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.geometry = Geometry.of(self.robot)
        self.client.on_warn(self._warn)

    def _warn(self, event: WarnEvent) -> None:
        self._warns.append(event.code)

    def close(self) -> None:
        """Stop listening to the client's warnings."""
        self.client.remove_listener(self._warn)

    def run(
        self, info: RunInfo, send: Callable[[], Command | str], duration: float, group: str, **meta: Any
    ) -> RunResult:
        """Mark, ``send()`` (the command, or a text naming what was sent), wait for IDLE and the
        coast-down, measure."""
        mark = self.truth.mark()
        latest = self.tap.latest
        counts = tuple(latest.encoders) if latest is not None and latest.encoders else None
        odo0 = self.tap.odometry_pose
        h0, t0 = self.tap.heading, self._ctime()
        self._warns.clear()
        command = send()
        self.client.wait_idle(timeout=4.0 * duration + 10.0)  # saturation stretches a motion
        self.wait_still()
        truth = self.truth.measure(mark, info) if self.truth.can(info) else None
        odo1, h1, t1 = self.tap.odometry_pose, self.tap.heading, self._ctime()
        odometry = None
        if odo0 is not None and odo1 is not None:
            odometry = relative(odo0.x, odo0.y, odo0.theta, odo1.x, odo1.y, odo1.theta, "encoders")
        result = RunResult(
            kind=info.kind,
            group=group,
            command=command if isinstance(command, str) else text.encode(command).decode("ascii").strip(),
            duration=duration,
            truth=truth,
            odometry=odometry,
            gyro=None if h0 is None or h1 is None else h1 - h0,
            gyro_time=None if t0 is None or t1 is None else t1 - t0,
            warnings=tuple(self._warns),
            counts=counts,
            **meta,
        )
        self.log.append(result)
        if self.progress is not None:
            self.progress.update(1)
        return result

    def move(
        self,
        what: str,
        length: float,
        speed: float,
        course_deg: float,
        group: str,
        detail: str = "",
        **meta: Any,
    ) -> RunResult:
        """A straight MOVE of ``length`` m at ``speed`` m/s on ``course_deg``, run as :meth:`run` (its
        ``course_deg`` in the result); described as ``<what>: move <cm> cm at <speed> m/s on course
        <course> deg<detail>``."""
        course = math.radians(course_deg)
        info = RunInfo(
            STRAIGHT,
            f"{what}: move {100 * length:.0f} cm at {speed:g} m/s on course {course_deg:g} deg{detail}",
            course,
        )
        send = partial(self.client.move, length, speed, course)
        return self.run(info, send, length / speed, group, course_deg=course_deg, **meta)

    def wait_still(self) -> None:
        """Wait ``settle`` s, then until no encoder count moves (a heavy robot coasts for long)."""
        self.client.sleep(self.settle)
        last = self.tap.counts()
        waited = self.settle
        while last is not None and waited < STILL_TIMEOUT:
            self.client.sleep(0.1)
            waited += 0.1
            now = self.tap.counts()
            if now is None or all(abs(a - b) <= 1 for a, b in zip(now, last, strict=True)):
                break
            last = now

    def _ctime(self) -> float | None:
        return self.tap.latest.controller_time if self.tap.latest is not None else None

    def power_run(
        self, powers: Sequence[int], duration: float, info: RunInfo, group: str, **meta: Any
    ) -> RunResult:
        """One POWER run: ``powers`` per motor for ``duration`` s, measured as :meth:`run` does."""
        return self.run(info, lambda: self.client.power(duration, powers), duration, group, **meta)

    def note(self, message: str) -> None:
        """Show what is running next to the progress bar."""
        if self.progress is not None:
            self.progress.set_postfix_str(message)
