"""Seed 002's dead reckoning as written: tracking wheels by its (8)-(12), the raw gyro heading by (1)."""

from __future__ import annotations

import math

from omnibot.errors import ConfigError
from omnibot.estimation.estimator import VELOCITY_TAU, SensorSample
from omnibot.estimation.tracking import Seed002Odometry
from omnibot.motion import Estimate, Pose2D
from omnibot.robot import RobotDescription


class Seed002Estimator:
    """Seed 002's dead reckoning as written: tracking wheels by (8)-(12), raw gyro heading by (1)."""

    def __init__(self, robot: RobotDescription, start: Pose2D | None = None, name: str = "seed002") -> None:
        if robot.gyro is None:
            raise ConfigError(f"robot {robot.name} has no gyro for seed 002's heading")
        self.name = name
        self.alerts: list[str] = []
        self.odometry = Seed002Odometry(robot, start)
        start = start or Pose2D(0.0, 0.0, 0.0)
        self.estimate = Estimate(0.0, start.x, start.y, start.theta)
        self._last: SensorSample | None = None
        self._vel = (0.0, 0.0, 0.0)

    @property
    def distance(self) -> float:
        """Distance travelled by the tracking wheels since the start, m."""
        return self.odometry.distance

    def update(self, sample: SensorSample) -> Estimate:
        """Fold in one sample: tracking-wheel increments for position, the raw gyro sum for heading."""
        last = self._last
        self._last = sample
        d_theta = 0.0
        if last is not None and sample.heading is not None and last.heading is not None:
            d_theta = sample.heading - last.heading
        if sample.tracking is None:
            return self.estimate
        before = self.odometry.pose
        pose = self.odometry.update(sample.tracking, d_theta)
        t = sample.controller_time
        dt = t - self.estimate.t if last is not None else 0.0
        if dt > 0:
            a = 1.0 - math.exp(-dt / VELOCITY_TAU)
            vx0, vy0, w0 = self._vel
            self._vel = (
                vx0 + a * ((pose.x - before.x) / dt - vx0),
                vy0 + a * ((pose.y - before.y) / dt - vy0),
                w0 + a * (d_theta / dt - w0),
            )
        self.estimate = Estimate(t, pose.x, pose.y, pose.theta, *self._vel, False, False)
        return self.estimate
