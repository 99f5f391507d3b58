"""The gyro's calibration spins watched (:class:`GyroProbe`): the gyro's heading and the encoders'
rotation at every telemetry sample, the standstills and spins between marks, fitted
(:func:`~omnibot.estimation.spins.fit_spins`) by :meth:`~omnibot.navigation.runner.Navigator.calibrate_gyro`.
"""

from __future__ import annotations

import numpy as np

from omnibot.client import Telemetry
from omnibot.estimation import GyroSilence, PoseEstimator, Spin, SpinFit, Standstill, fit_spins
from omnibot.robot import RobotDescription


class GyroProbe:
    """The gyro's heading and the encoders' rotation at every telemetry sample (gyro calibration)."""

    def __init__(self, robot: RobotDescription) -> None:
        self._encoders = PoseEstimator(robot, translation="encoders", heading="encoders", name="gyro-probe")
        self.rows: list[tuple[float, float, float]] = []  # controller time, gyro heading, encoder heading
        self.silence = GyroSilence()

    def update(self, event: Telemetry) -> None:
        """Take a telemetry sample (one with the gyro's heading)."""
        if event.heading is None:
            return
        before = self._encoders.estimate.theta
        est = self._encoders.update(event)
        self.silence.update(event.heading, est.theta - before)
        self.rows.append((event.controller_time, event.heading, est.theta))

    def mark(self) -> int:
        """The index of the latest sample (a standstill's or a spin's start or end)."""
        return len(self.rows) - 1

    def fit(self, marks: list[int], moving: list[float]) -> SpinFit | None:
        """The spins' fit (:func:`~omnibot.estimation.spins.fit_spins`) from ``marks``: the start and
        end of a standstill, then of each spin's standstill after it (the spin between the two, its
        wheels turning ``moving`` s); None without enough telemetry."""
        if len(self.rows) < 10 or min(marks) < 0 or len(marks) != 2 * len(moving) + 2:
            return None
        rows = np.array(self.rows)

        def still(i: int, j: int) -> Standstill:
            t, psi = rows[i : j + 1, 0], rows[i : j + 1, 1]
            slope = float(np.polyfit(t - t[0], psi, 1)[0])
            duration = float(t[-1] - t[0])
            return Standstill(slope * duration, duration, float(t[[0, -1]].mean()))

        standstills = [still(i, j) for i, j in zip(marks[::2], marks[1::2], strict=True)]
        spins = [
            Spin(
                gyro=float(rows[j, 1] - rows[i, 1]),
                encoders=float(rows[j, 2] - rows[i, 2]),
                duration=float(rows[j, 0] - rows[i, 0]),
                moving=m,
                time=float(rows[[i, j], 0].mean()),
            )
            for i, j, m in zip(marks[1:-1:2], marks[2::2], moving, strict=True)
        ]
        if min(s.duration for s in standstills) <= 0:
            return None
        return fit_spins(standstills, spins)
