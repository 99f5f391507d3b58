"""Dead reckoning from passive tracking wheels (seed 002's "vertical" and "horizontal" encoders).

Seed 002, equations (8)-(12): each encoder's pulses times the distance per pulse 2 pi R / PPR (8)-(10)
are added straight onto the world coordinates (11)-(12), assuming the heading never changes. Two
things break that when the robot turns: the increments are body-frame distances (they must be turned
by the heading), and a wheel mounted at p off the centre also rolls with the rotation, w x p, which is
not translation at all. With the rotation increment d_theta known (from the gyro), wheel k rolls

    s_k = u_k . (d + d_theta z x p_k) = u_k . d + d_theta (p_k x u_k)

for a body displacement d (twist times the interval), so ``u_k . d = s_k - d_theta lever_k`` with
lever_k = p_k x u_k; two or more non-parallel wheels give d by least squares, and the pose is moved
along the arc (:func:`~omnibot.estimation.odometry.compose_arc`). :class:`TrackingOdometry` does that;
:class:`Seed002Odometry` is the seed's equations as written, kept as the baseline to beat.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from omnibot.errors import ConfigError
from omnibot.estimation.odometry import CountTracker, compose_arc
from omnibot.motion import Pose2D
from omnibot.robot import RobotDescription, TrackingWheelSpec


class TrackingGeometry:
    """Directions, levers and metres per count of a robot's tracking wheels."""

    def __init__(self, specs: Sequence[TrackingWheelSpec], robot_name: str = "robot") -> None:
        if len(specs) < 2:
            raise ConfigError(
                f"tracking-wheel odometry needs at least two tracking wheels; {robot_name} has {len(specs)}"
            )
        self.u = np.array([(math.cos(s.direction), math.sin(s.direction)) for s in specs])
        if np.linalg.matrix_rank(self.u) < 2:
            raise ConfigError(
                f"the tracking wheels of {robot_name} are parallel: they cannot measure 2D motion"
            )
        self.p = np.array([(s.x, s.y) for s in specs])
        self.lever = self.p[:, 0] * self.u[:, 1] - self.p[:, 1] * self.u[:, 0]
        self.m_per_count = np.array([2.0 * math.pi * s.radius / s.counts_per_rev for s in specs])
        self.pinv = np.linalg.pinv(self.u)
        self.n = len(specs)

    def displacement(self, rolled: np.ndarray, dtheta: float) -> tuple[float, float]:
        """Body displacement (dx, dy) from the distances the wheels rolled (m) and the rotation (rad)."""
        d = self.pinv @ (rolled - dtheta * self.lever)
        return float(d[0]), float(d[1])

    def naive(self, rolled: np.ndarray) -> tuple[float, float]:
        """Seed 002's reading: the rolled distances are the displacement (no rotation term)."""
        d = self.pinv @ rolled
        return float(d[0]), float(d[1])


class TrackingOdometry:
    """Pose from tracking-wheel counts and a rotation increment per interval (from the gyro)."""

    def __init__(self, robot: RobotDescription, start: Pose2D | None = None) -> None:
        self.geometry = TrackingGeometry(robot.encoders.tracking, robot.name)
        self.pose = start or Pose2D(0.0, 0.0, 0.0)
        self.distance = 0.0
        self._counts = CountTracker(self.geometry.n, "tracking")

    def update(self, counts: Sequence[int], dtheta: float) -> Pose2D:
        """Fold in new cumulative counts and the rotation (rad) since the last call; the new pose."""
        delta = self._counts.step(counts)
        if delta is None:
            return self.pose
        rolled = delta * self.geometry.m_per_count
        dx, dy = self.geometry.displacement(rolled, dtheta)
        self.pose = compose_arc(self.pose, dx, dy, dtheta)
        self.distance += math.hypot(dx, dy)
        return self.pose


class Seed002Odometry:
    """Seed 002's dead reckoning as written: X += d_vert (11), Y += d_horz (12), heading += d_theta (1).

    The tracking-wheel increments are added in the frame of the start heading ("we shall consider the
    orientation of the robot to be constant"), whatever the robot's rotation; the heading is the raw
    gyro sum of equation (1) and is only reported (for heading hold), never used for position.
    """

    def __init__(self, robot: RobotDescription, start: Pose2D | None = None) -> None:
        self.geometry = TrackingGeometry(robot.encoders.tracking, robot.name)
        self.pose = start or Pose2D(0.0, 0.0, 0.0)
        self._frame = self.pose.theta
        self.distance = 0.0
        self._counts = CountTracker(self.geometry.n, "tracking")

    def update(self, counts: Sequence[int], dtheta: float) -> Pose2D:
        """Fold in new cumulative counts (added in the start heading's frame) and the rotation (rad)
        since the last call (added to the heading only); the new pose."""
        delta = self._counts.step(counts)
        if delta is None:
            return self.pose
        rolled = delta * self.geometry.m_per_count
        dv, dh = self.geometry.naive(rolled)
        cs, sn = math.cos(self._frame), math.sin(self._frame)
        p = self.pose
        self.pose = Pose2D(p.x + cs * dv - sn * dh, p.y + sn * dv + cs * dh, p.theta + dtheta)
        self.distance += math.hypot(dv, dh)
        return self.pose
