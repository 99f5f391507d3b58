"""Dead reckoning from motor-shaft encoders through the forward kinematics, with optional gyro heading.

Each update takes cumulative encoder counts (and, when there is one, the gyro's integrated heading)
at a time stamp. Count differences become wheel angle increments, the least-squares forward
kinematics turns them into a body displacement (dx, dy, dtheta), and the displacement is composed
onto the pose along a constant-curvature arc (exact for a constant twist over the interval, so the
estimate does not assume a constant heading as seed 002's equations (11)-(12) do). With a gyro
heading the rotation comes from the gyro and only the translation from the wheels. The per-wheel
residual of the fit (what no rigid motion explains) is kept as a slip signal; :attr:`WheelOdometry.slipping`
says when its studentised form is larger than encoder quantisation explains
(:mod:`~omnibot.estimation.wheelslip`; only robots with more wheels than the three planar motions
have a residual at all).

Counts are signed 32-bit and wrap (docs/protocol.md, TEL); differences are taken modulo 2**32.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from omnibot import motion
from omnibot.errors import ConfigError
from omnibot.estimation.wheelslip import WheelSlipCheck
from omnibot.robot import RobotDescription
from omnibot.robot import kinematics as kin

COUNT_MODULUS = 1 << 32

Pose2D = motion.Pose2D
"""The planar pose (:class:`omnibot.motion.Pose2D`; named here too for older imports)."""


def count_delta(new: np.ndarray, old: np.ndarray) -> np.ndarray:
    """``new - old`` for signed 32-bit wrapping counters (any step smaller than 2**31)."""
    out: np.ndarray = (new - old + COUNT_MODULUS // 2) % COUNT_MODULUS - COUNT_MODULUS // 2
    return out


class CountTracker:
    """Increments of cumulative, wrapping counters, sample to sample (None for the first sample)."""

    def __init__(self, n: int, what: str) -> None:
        self.n = n
        self.what = what
        self._last: np.ndarray | None = None

    def step(self, counts: Sequence[int]) -> np.ndarray | None:
        """Counts since the previous sample; None for the first one. ValueError for a wrong count."""
        c = np.asarray(counts, dtype=float)
        if c.shape != (self.n,):
            raise ValueError(f"expected {self.n} {self.what} counts, got {c.size}")
        last, self._last = self._last, c
        return None if last is None else count_delta(c, last)


def compose_arc(pose: Pose2D, dx: float, dy: float, dtheta: float) -> Pose2D:
    """Move ``pose`` by a body-frame displacement travelled with constant twist (an arc)."""
    if abs(dtheta) < 1e-9:
        a, b = 1.0 - dtheta * dtheta / 6.0, dtheta / 2.0
    else:
        a, b = math.sin(dtheta) / dtheta, (1.0 - math.cos(dtheta)) / dtheta
    # the chord of the arc, in the body frame at the start of the interval
    cx, cy = a * dx - b * dy, b * dx + a * dy
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    return Pose2D(pose.x + c * cx - s * cy, pose.y + s * cx + c * cy, pose.theta + dtheta)


class WheelOdometry:
    """Pose from cumulative motor-encoder counts (every driven wheel needs an encoder)."""

    def __init__(self, robot: RobotDescription, start: Pose2D | None = None) -> None:
        cpr = {e.wheel: e.counts_per_rev for e in robot.encoders.motors}
        missing = [w.name for w in robot.wheels if w.name not in cpr]
        if missing:
            raise ConfigError(f"wheel odometry needs an encoder on every wheel; none on {', '.join(missing)}")
        self._rad_per_count = np.array([2.0 * math.pi / cpr[w.name] for w in robot.wheels])
        self._pinv = kin.forward_matrix(robot)
        self._J = robot.wheel_matrix
        self.pose = start or Pose2D(0.0, 0.0, 0.0)
        self.distance = 0.0
        """Path length travelled by the body centre, m."""
        self._residual = np.zeros(robot.n_wheels)
        self._slip_check = WheelSlipCheck(self._J, self._rad_per_count, window=0.0)
        self._last: tuple[np.ndarray, np.ndarray] | None = None  # (angles, disp) not yet checked
        self._counts = CountTracker(robot.n_wheels, "encoder")
        self._heading: float | None = None

    def update(self, counts: Sequence[int], heading: float | None = None) -> Pose2D:
        """Fold in new cumulative counts (and the gyro's integrated heading, rad); the new pose."""
        delta = self._counts.step(counts)
        if delta is None:
            self._heading = heading
            return self.pose
        angles = delta * self._rad_per_count
        disp = self._pinv @ angles  # body displacement: twist times the interval
        self._last = (angles, disp)  # the residual and its check on demand: they see this interval alone
        dx, dy, dtheta = disp.tolist()
        if heading is not None and self._heading is not None:
            dtheta = heading - self._heading
        self._heading = heading
        self.pose = compose_arc(self.pose, dx, dy, dtheta)
        self.distance += math.hypot(dx, dy)
        return self.pose

    @property
    def residual(self) -> np.ndarray:
        """Last interval's per-wheel residual, rad (non-zero: the wheels disagree, slip)."""
        self._check_last()
        return self._residual

    @property
    def slip_check(self) -> WheelSlipCheck:
        """The residual's slip check, one interval at a time (:mod:`~omnibot.estimation.wheelslip`)."""
        self._check_last()
        return self._slip_check

    @property
    def slipping(self) -> bool:
        """True when the last interval's studentised residual is more than quantisation explains
        (a wheel slipped)."""
        return self.slip_check.slipping

    def _check_last(self) -> None:
        """The residual and slip check of the last interval, when first asked for (a check of
        window 0 keeps that interval alone, so skipping the ones before changes nothing)."""
        if self._last is not None:
            angles, disp = self._last
            self._last = None
            self._residual = angles - self._J @ disp
            self._slip_check.update(angles, 0.0)


def forward_twist(robot: RobotDescription, wheel_speeds: Sequence[float]) -> kin.ForwardResult:
    """Body twist for wheel speeds (rad/s), a convenience over :func:`omnibot.robot.kinematics.forward`."""
    return kin.forward(robot.wheel_matrix, wheel_speeds)
