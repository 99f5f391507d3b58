"""The motor map, fitted: each motor's dead-band offset and the gain tables that balance unequal
motors (pure functions, no I/O; :mod:`omnibot.calibration.motors` drives the runs).

The firmware gives motor i ``sign(a) (offset_i + gain_i(|a|) |a|)`` for the nominal power ``a``
of the calibration factors (docs/firmware.md); :func:`omnibot.calibration.patterns.map_power` is the
same on the host.

* **Offsets.** ``offset_i = deadband_i * rotation / mean(deadband)`` (:func:`offsets_from_deadbands`):
  each motor's dead band alone, scaled so that their mean is the dead band of rotation in place.
* **Gains.** The balance runs' errors (:func:`balance_errors`: each run's course error and its turn
  per metre) and the Gauss-Newton step on the log-gains, their sum held at zero (:func:`gain_step`).
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from omnibot.calibration.patterns import Geometry
from omnibot.calibration.runs import Motion
from omnibot.robot.description import MotorMapSpec, PiecewiseLinear

GAIN_STEP = 0.08
"""Log-gain step of the finite-difference Jacobian."""
GAIN_LIMIT = 0.4
"""abs(log-gain) is kept below this (a factor 1.5)."""
MIN_DISTANCE = 0.02
"""m: a balance run shorter than this tells nothing."""


def identity(n: int) -> MotorMapSpec:
    """The motor map that changes nothing: no offsets, gain 1 for each of ``n`` motors."""
    return MotorMapSpec(offset=(0.0,) * n, gain=(PiecewiseLinear(x=(0.0,), y=(1.0,)),) * n)


# --------------------------------------------------------------------------- offsets


def offsets_from_deadbands(single: Sequence[int], rotation: int, pwm_max: int) -> tuple[float, ...]:
    """``offset_i = deadband_i * rotation / mean(deadband)`` (see the module docstring), 0.1 counts;
    all zero when a motor never moved the robot alone."""
    if not single or any(d > pwm_max for d in single) or rotation > pwm_max:
        return (0.0,) * len(single)
    mean = statistics.fmean(single)
    return tuple(round(d * rotation / mean, 1) for d in single)


def balance_courses(geometry: Geometry, folded: Sequence[float] | None = None) -> list[float]:
    """Raw courses (degrees) of the balance runs: each folded course (default: 0 and the largest)
    from every idle axis, both ways."""
    axes = sorted(a % 180.0 for a in geometry.idle_axes)
    out: list[float] = []
    for a in axes:
        for f in folded if folded is not None else (0.0, geometry.fold_max):
            c = a + f
            out += [round(c % 360.0, 6), round((c + 180.0) % 360.0, 6)]
    return sorted(set(out))


@dataclass
class Balance:
    """The balance runs' outcome: the gain table of each motor and the errors before and after."""

    powers: list[int] = field(default_factory=list)
    log_gains: list[list[float]] = field(default_factory=list)
    """Per power, each motor's log-gain."""
    before: list[float] = field(default_factory=list)
    """Per power, the rms error (rad) with equal gains."""
    after: list[float] = field(default_factory=list)
    """Per power, the rms error (rad) with the fitted gains."""

    def as_dict(self) -> dict[str, list[Any]]:
        """The outcome as plain data (for the JSON report)."""
        return {
            "powers": self.powers,
            "log_gains": self.log_gains,
            "before": self.before,
            "after": self.after,
        }

    def tables(self, n: int) -> tuple[PiecewiseLinear, ...]:
        """Each of ``n`` motors' gain table (exp of its log-gains per power); identity when nothing was
        fitted."""
        if not self.powers:
            return identity(n).gain
        xs = tuple(float(p) for p in self.powers)
        return tuple(
            PiecewiseLinear(x=xs, y=tuple(round(math.exp(g[i]), 3) for g in self.log_gains)) for i in range(n)
        )


def balance_errors(m: Motion | None, course_deg: float) -> list[float]:
    """Course error (rad) and turn (rad per metre of path) of one balance run on ``course_deg``;
    NaN where the robot hardly moved or the truth cannot tell."""
    if m is None or m.x is None or m.y is None or m.theta is None or (m.distance or 0.0) < MIN_DISTANCE:
        return [math.nan, math.nan]
    course = math.atan2(m.y, m.x) - 0.5 * m.theta  # the body-frame course of an arc
    err = (course - math.radians(course_deg) + math.pi) % (2 * math.pi) - math.pi
    return [err, m.theta / max(m.path or m.distance or 0.0, MIN_DISTANCE)]


def gain_step(jac: np.ndarray, e: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The log-gains after one Gauss-Newton step on the errors ``e`` (Jacobian ``jac``), their sum
    held at 0, clipped to :data:`GAIN_LIMIT`; rows with a NaN are left out."""
    n = x.size
    rows = np.isfinite(e) & np.all(np.isfinite(jac), axis=1)
    a = np.vstack([jac[rows], np.ones((1, n))])  # the last row holds the sum of log-gains at 0
    step = np.linalg.lstsq(a, -np.concatenate([e[rows], [x.sum()]]), rcond=None)[0]
    return np.asarray(np.clip(x + step, -GAIN_LIMIT, GAIN_LIMIT))


def constant_gains(offsets: Sequence[float], x: np.ndarray) -> MotorMapSpec:
    """A motor map with ``offsets`` and one constant gain per motor, exp of ``x``."""
    gains = tuple(PiecewiseLinear(x=(0.0,), y=(float(math.exp(v)),)) for v in x)
    return MotorMapSpec(offset=tuple(offsets), gain=gains)


def rms(e: np.ndarray) -> float:
    """Root mean square of the finite values of ``e`` (inf when there are none)."""
    ok = e[np.isfinite(e)]
    return float(np.sqrt(np.mean(ok * ok))) if ok.size else math.inf
