"""Gyro bias and scale calibration.

The controller reports the yaw rate (TEL gyro group) and its integral (TEL heading). The model is
the usual one for a MEMS gyro::

    measured = true / scale + bias        so    true = scale * (measured - bias)

* bias: the mean rate over a standstill (``Plan.gyro_still`` s, :func:`omnibot.calibration.tap.standstill_bias`);
* scale: over rotations whose true angle is known (the rotation test, measured by the truth
  strategy), least squares of true angle against the bias-corrected integrated angle
  ``gyro_heading_change - bias * duration``;
* the navigator's spin in place (:func:`omnibot.estimation.spins.fit_spins`): bias from the
  standstills around the spins, scale error and the floor's creep from spins at two rates against
  the encoders' rotation.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

from omnibot.calibration.runs import RunResult


@dataclass(frozen=True)
class GyroCalibration:
    """The gyro's calibration: standstill bias (rad/s) with its uncertainty, and scale from rotations."""

    bias: float
    """rad/s read at standstill."""
    bias_std: float
    """Standard deviation of the bias estimate (of the mean), rad/s."""
    samples: int
    scale: float | None
    """true rate = scale * (measured - bias); None without a rotation of known angle."""
    rotations: int = 0

    def correct(self, measured: float) -> float:
        """A measured rate (rad/s) corrected."""
        return (self.scale or 1.0) * (measured - self.bias)

    def as_dict(self) -> dict[str, Any]:
        """The calibration as plain data (for the calibration file)."""
        return asdict(self)


def fit_scale(runs: Sequence[RunResult], bias: float) -> tuple[float | None, int]:
    """Scale from runs with a true angle and a gyro angle (the rotation test); (None, 0) if none."""
    num = den = 0.0
    used = 0
    for r in runs:
        if r.truth is None or r.truth.theta is None or r.gyro is None or r.gyro_time is None:
            continue
        g = r.gyro - bias * r.gyro_time
        if abs(g) < math.radians(30.0):
            continue
        num += r.truth.theta * g
        den += g * g
        used += 1
    return (num / den if den > 0 else None), used


def calibrate_gyro(bias: tuple[float, float, int], runs: Sequence[RunResult]) -> GyroCalibration:
    """The gyro calibration from a standstill bias ``(mean, std, samples)`` and the rotation test's runs."""
    scale, used = fit_scale(runs, bias[0])
    return GyroCalibration(bias=bias[0], bias_std=bias[1], samples=bias[2], scale=scale, rotations=used)
