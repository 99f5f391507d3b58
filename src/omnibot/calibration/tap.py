"""The controller's telemetry during calibration: latest TEL sample, wheel odometry, gyro, sonar, logs.

One :class:`TelemetryTap` per client switches TEL on (encoders, gyro rate, integrated heading,
sonar ranges, queue state every ``period`` s) and listens: it keeps the latest sample, runs wheel
odometry on the encoder counts when every wheel has an encoder, and can record the samples of a
stretch of time (a square run, a standstill) for later replay.
"""

from __future__ import annotations

import math
import statistics

from omnibot.client import RobotClient, Telemetry
from omnibot.estimation import WheelOdometry
from omnibot.motion import Pose2D
from omnibot.protocol import codes
from omnibot.robot import RobotDescription

TAP_MASK = (
    codes.TEL_ENCODERS
    | codes.TEL_TRACKING
    | codes.TEL_GYRO
    | codes.TEL_HEADING
    | codes.TEL_SONAR
    | codes.TEL_QUEUE
)


class TelemetryTap:
    """Telemetry listener of one client (see the module docstring)."""

    def __init__(self, client: RobotClient, robot: RobotDescription, period: float = 0.02) -> None:
        self.client = client
        self.robot = robot
        self.period = period
        self.latest: Telemetry | None = None
        self.odometry = WheelOdometry(robot) if robot.has_wheel_encoders else None
        self.gyro = robot.gyro is not None
        self._log: list[Telemetry] | None = None
        self._extra: list[WheelOdometry] = []
        self._on = False

    def start(self) -> None:
        """Switch TEL on and start listening."""
        if not self._on:
            self.client.on_telemetry(self._sample)
            self.client.telemetry(self.period, TAP_MASK)
            self._on = True
            self.client.sleep(3 * self.period)

    def stop(self) -> None:
        """Switch TEL off and stop listening."""
        if self._on:
            self._on = False
            self.client.remove_listener(self._sample)
            self.client.telemetry(0.0)

    def _sample(self, tel: Telemetry) -> None:
        self.latest = tel
        if tel.encoders is not None:
            if self.odometry is not None:
                self.odometry.update(tel.encoders, None)
            for odo in self._extra:
                odo.update(tel.encoders, None)
        if self._log is not None:
            self._log.append(tel)

    def add_odometry(self, robot: RobotDescription) -> WheelOdometry:
        """Another wheel odometry on the same counts, with ``robot``'s geometry (corrected radii)."""
        odo = WheelOdometry(robot)
        if self.latest is not None and self.latest.encoders is not None:
            odo.update(self.latest.encoders, None)
        self._extra.append(odo)
        return odo

    # ------------------------------------------------------------------ views

    @property
    def odometry_pose(self) -> Pose2D | None:
        """The pose of the tap's encoder odometry, None without one."""
        return self.odometry.pose if self.odometry is not None else None

    def counts(self) -> tuple[int, ...] | None:
        """The latest encoder and tracking-wheel counts together, None when there are none."""
        tel = self.latest
        if tel is None:
            return None
        counts = (tel.encoders or ()) + (tel.tracking or ())
        return counts or None

    @property
    def heading(self) -> float | None:
        """The controller's integrated gyro heading (rad), None without a gyro or a sample."""
        if not self.gyro or self.latest is None:
            return None
        return self.latest.heading

    def record(self) -> None:
        """Start keeping every sample (see :meth:`take_log`)."""
        self._log = []

    def take_log(self) -> list[Telemetry]:
        """The samples since :meth:`record`, and stop keeping them."""
        log, self._log = self._log or [], None
        return log

    def collect(self, seconds: float) -> list[Telemetry]:
        """Let ``seconds`` pass and return the samples that came meanwhile."""
        self.record()
        self.client.sleep(seconds)
        return self.take_log()


def replay_odometry(
    robot: RobotDescription, log: list[Telemetry], start: Pose2D | None = None
) -> Pose2D | None:
    """Wheel odometry over recorded samples with ``robot``'s geometry (e.g. corrected radii)."""
    if not robot.has_wheel_encoders:
        return None
    odo = WheelOdometry(robot, start=start)
    for tel in log:
        if tel.encoders is not None:
            odo.update(tel.encoders, None)
    return odo.pose


def standstill_bias(tap: TelemetryTap, seconds: float) -> tuple[float, float, int] | None:
    """(mean rate, its standard error, samples) over ``seconds`` of standstill; None without a gyro."""
    rates = [t.gyro_rate for t in tap.collect(seconds) if t.gyro_rate is not None]
    if not tap.gyro or len(rates) < 2:
        return None
    return statistics.fmean(rates), statistics.stdev(rates) / math.sqrt(len(rates)), len(rates)
