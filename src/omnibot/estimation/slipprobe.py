"""What the slip fit needs from telemetry (:class:`SlipProbe`): an uncorrected encoders+gyro pose
estimator's twist, acceleration, heading and pose at every sample, cut into runs
(:class:`~omnibot.estimation.slip.SlipLeg`) for :func:`~omnibot.estimation.slip.fit_slip`.

Its own module, above both :mod:`~omnibot.estimation.slip` (the model) and
:mod:`~omnibot.estimation.estimator` (which applies it), so that neither imports the other back.
"""

from __future__ import annotations

import numpy as np

from omnibot.errors import ConfigError
from omnibot.estimation.estimator import PoseEstimator
from omnibot.estimation.slip import SlipLeg
from omnibot.robot import RobotDescription


class SlipProbe:
    """Records what the slip fit needs from telemetry: an uncorrected encoders+gyro estimator's body
    twist, acceleration, heading and pose at every sample; :meth:`leg` cuts a run out of it."""

    def __init__(self, robot: RobotDescription) -> None:
        self.robot = robot
        self.estimator = PoseEstimator(robot, translation="encoders", name="slip-probe")
        self._rows: list[tuple[float, float, float, float, float, float, float, float, float, float]] = []
        self._t: float | None = None

    def update(self, sample: object) -> None:
        """Fold in one telemetry sample (anything with the attributes of a ``SensorSample``)."""
        est = self.estimator.update(sample)  # type: ignore[arg-type]
        dt = 0.0 if self._t is None else est.t - self._t
        self._t = est.t
        q, a = self.estimator.body_velocity, self.estimator.body_acceleration
        self._rows.append((dt, q[0], q[1], q[2], a[0], a[1], a[2], est.theta, est.x, est.y))

    def mark(self) -> int:
        """The index of the next sample: where a run starts."""
        return len(self._rows)

    def heading(self, start: int) -> float:
        """The estimated heading (rad) at a run's start (the sample before mark ``start``)."""
        if not self._rows:
            raise ConfigError("a slip calibration run needs telemetry: is TEL on?")
        return float(self._rows[min(max(start - 1, 0), len(self._rows) - 1)][7])

    def leg(self, start: int, true_disp: tuple[float, float]) -> SlipLeg:
        """The run from sample ``start`` to now, with its true (x, y) displacement (estimator frame)."""
        rows = np.array(self._rows[max(start - 1, 0) :])
        if len(rows) < 2:
            raise ConfigError("a slip calibration run needs telemetry: is TEL on?")
        body = rows[1:]
        disp = (float(rows[-1, 8] - rows[0, 8]), float(rows[-1, 9] - rows[0, 9]))
        return SlipLeg(
            twists=body[:, 1:4],
            accels=body[:, 4:7],
            dt=body[:, 0],
            headings=body[:, 7],
            encoder_disp=disp,
            true_disp=true_disp,
        )
