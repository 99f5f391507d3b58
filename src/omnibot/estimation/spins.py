"""The gyro's bias, scale error and the floor's creep from spins in place (the navigator's gyro
calibration, :meth:`omnibot.navigation.runner.Navigator.calibrate_gyro`): bias from the standstills
around the spins, scale error and creep from spins at two rates against the encoders' rotation.
The rest of the gyro's calibration (standstill bias, scale from measured rotations) is
:mod:`omnibot.calibration.gyro`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Standstill:
    """A stretch with the body still (around the gyro spin's turns): the gyro's heading change over
    it (rad), its length (s) and its middle on the controller's clock (s). What the gyro reads then
    is its bias alone."""

    gyro: float
    duration: float
    time: float

    @property
    def bias(self) -> float:
        """rad/s: the gyro's mean rate over the standstill."""
        return self.gyro / self.duration


@dataclass(frozen=True)
class Spin:
    """One turn in place of the gyro spin, from the end of one standstill to the start of the next:
    the gyro's and the encoders' heading change over it (rad), its length and the time the wheels
    turned (s), and its middle on the controller's clock (s)."""

    gyro: float
    encoders: float
    duration: float
    moving: float
    time: float


@dataclass(frozen=True)
class SpinFit:
    """The spin's fit: the bias from the standstills, and ``gyro - bias T = (1 + scale_error) true``
    with the true rotation ``encoders + creep * moving * sign``."""

    bias: float
    """rad/s: the gyro's bias at the last standstill (the one the robot leaves the manoeuvre with)."""
    scale_error: float
    creep: float
    """rad/s the body turns beyond the encoders' rotation while it spins (floor creep; 0 if not fitted)."""
    turned: float
    """rad: the body's rotation over the spins, from the gyro (its bias and scale error corrected)."""

    def true_rotation(self, spin: Spin) -> float:
        """The body's rotation over ``spin`` by its encoders: theirs plus the creep."""
        return spin.encoders + math.copysign(self.creep * spin.moving, spin.encoders)


def spin_biases(standstills: Sequence[Standstill], spins: Sequence[Spin]) -> list[float]:
    """The gyro's mean bias over each spin (rad/s): the standstills' biases, one before and one after
    every spin, interpolated linearly in time to the spin's middle (the bias walks)."""
    if len(standstills) != len(spins) + 1:
        raise ValueError(f"{len(spins)} spins need {len(spins) + 1} standstills, not {len(standstills)}")
    if any(s.duration <= 0 for s in standstills):
        raise ValueError("a standstill must last a while")
    out = []
    for before, spin, after in zip(standstills, spins, standstills[1:], strict=False):
        span = after.time - before.time
        w = (spin.time - before.time) / span if span > 0 else 0.5
        out.append((1.0 - w) * before.bias + w * after.bias)
    return out


def fit_spins(standstills: Sequence[Standstill], spins: Sequence[Spin]) -> SpinFit:
    """Gyro bias and scale error from spins in place with a standstill before and after each, with the
    floor's creep when it can be told apart.

    Still, the gyro reads its bias alone: the standstills pin it (and its walk) without the encoders,
    whose error over the spins would otherwise read as bias times the manoeuvre's length (omni4 on
    carpet: 0.18 degree). With each spin's bias known, the spins' gyro-minus-encoder differences give
    the scale error and the creep. On a floor whose rollers roll against a large resistance (a
    mecanum wheel on carpet) the wheels creep all the time the body turns: the body turns at a
    near-constant rate beyond the encoders' rotation (mecanum4 on carpet: 0.02 rad/s, 2 % of a spin at
    1 rad/s, 4 % at 0.5 rad/s). With one spin rate that creep is a fixed fraction of the rotation and
    reads as a gyro scale error; spins at two rates (different ``moving`` time for the same angle)
    separate the two. With one rate the creep is taken as 0. The body's rotation over the spins is the
    gyro's, bias- and scale-corrected: a turn each way cancels the scale's share, and what is left is
    the gyro's noise and the bias's walk between standstills.
    """
    if not spins:
        raise ValueError("a gyro fit needs spins")
    biases = spin_biases(standstills, spins)
    a = np.array([[s.encoders, math.copysign(s.moving, s.encoders)] for s in spins])
    rhs = np.array([s.gyro - b * s.duration - s.encoders for s, b in zip(spins, biases, strict=True)])
    rates = [abs(s.encoders) / s.moving for s in spins if s.moving > 0]
    if not rates or max(rates) < 1.2 * min(rates):  # one rate: the creep cannot be told from the scale
        a = a[:, :1]
    solution, *_ = np.linalg.lstsq(a, rhs, rcond=None)
    scale_error = float(solution[0])
    creep = float(solution[1]) / (1.0 + scale_error) if a.shape[1] == 2 else 0.0
    turned = sum(s.gyro - b * s.duration for s, b in zip(spins, biases, strict=True)) / (1.0 + scale_error)
    return SpinFit(bias=standstills[-1].bias, scale_error=scale_error, creep=creep, turned=turned)
