"""Gyro bias and scale calibration.

The controller reports the yaw rate (TEL gyro group) and its integral (TEL heading). The model is
the usual one for a MEMS gyro::

    measured = true / scale + bias        so    true = scale * (measured - bias)

* bias: the mean rate over a standstill (``Plan.gyro_still`` s, :func:`omnibot.calibration.tap.standstill_bias`);
* scale: over rotations whose true angle is known (the rotation test, measured by the truth
  strategy), least squares of true angle against the bias-corrected integrated angle
  ``gyro_heading_change - bias * duration``;
* the navigator's spin in place (:func:`fit_spins`): bias, scale error and the floor's creep from
  spins at two rates against the encoders' rotation.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

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


@dataclass(frozen=True)
class Spin:
    """One stretch of the gyro spin (turn in place from rest to rest, then stand still): the gyro's
    and the encoders' heading change over it (rad), its length and the time the wheels turned (s)."""

    gyro: float
    encoders: float
    duration: float
    moving: float


@dataclass(frozen=True)
class SpinFit:
    """The spin's least-squares fit: ``gyro = (1 + scale_error) true + bias T`` with the true rotation
    ``encoders + creep * moving * sign``."""

    bias: float
    """rad/s."""
    scale_error: float
    creep: float
    """rad/s the body turns beyond the encoders' rotation while it spins (floor creep; 0 if not fitted)."""

    def true_rotation(self, spin: Spin) -> float:
        """The body's rotation over ``spin``: the encoders' plus the creep."""
        return spin.encoders + math.copysign(self.creep * spin.moving, spin.encoders)


def fit_spins(standstill: float | None, standstill_gyro: float, spins: Sequence[Spin]) -> SpinFit:
    """Gyro bias and scale error from spins in place, with the floor's creep when it can be told apart.

    On a floor whose rollers roll against a large resistance (a mecanum wheel on carpet) the wheels
    creep all the time the body turns: the body turns at a near-constant rate beyond the encoders'
    rotation (mecanum4 on carpet: 0.02 rad/s, 2 % of a spin at 1 rad/s, 4 % at 0.5 rad/s). With one
    spin rate that creep is a fixed fraction of the rotation and reads as a gyro scale error; spins
    at two rates (different ``moving`` time for the same angle) separate the two. With one rate the
    creep is taken as 0. ``standstill`` is the time (s) of a standstill before the spins (None if
    none) and ``standstill_gyro`` the gyro's heading change over it.
    """
    rows: list[list[float]] = []
    rhs: list[float] = []
    if standstill is not None and standstill > 0:
        rows.append([0.0, standstill, 0.0])
        rhs.append(standstill_gyro)
    for s in spins:
        rows.append([s.encoders, s.duration, math.copysign(s.moving, s.encoders)])
        rhs.append(s.gyro - s.encoders)
    if not rows:
        raise ValueError("a gyro fit needs a standstill or spins")
    a = np.array(rows)
    rates = [abs(s.encoders) / s.moving for s in spins if s.moving > 0]
    if not rates or max(rates) < 1.2 * min(rates):  # one rate: the creep cannot be told from the scale
        a = a[:, :2]
    solution, *_ = np.linalg.lstsq(a, np.array(rhs), rcond=None)
    scale_error, bias = float(solution[0]), float(solution[1])
    creep = float(solution[2]) / (1.0 + scale_error) if a.shape[1] == 3 else 0.0
    return SpinFit(bias=bias, scale_error=scale_error, creep=creep)
