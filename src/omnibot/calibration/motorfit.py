"""The motor map, fitted: each motor's dead-band offset and its two-number motor model (pure
functions, no I/O; :mod:`omnibot.calibration.motors` drives the runs).

The firmware gives motor i ``sign(a) (offset_i + gain_i(|a|) |a|) + speed_i u_i`` for the nominal
power ``a`` of the calibration factors and the wheel's rim speed ``u_i`` (docs/firmware.md);
:func:`omnibot.calibration.patterns.map_power` is the same on the host.

* **Offsets.** ``offset_i = deadband_i * rotation / mean(deadband)`` (:func:`offsets_from_deadbands`):
  each motor's dead band alone, scaled so that their mean is the dead band of rotation in place.
* **The motor model.** A DC motor through its driver needs ``P = R tau / (k G) + k G omega`` (in PWM
  counts: the load's torque through the winding's resistance, and the back-EMF), so a motor whose
  torque constant is ``s`` times the nominal one needs ``a_load / s + s a_emf`` where the nominal
  motor needs ``a = a_load + a_emf``: ``a / s + (s - 1/s) E u`` with ``E u = a_emf`` (E: the nominal
  back-EMF in counts per m/s of rim speed). One constant gain ``1/s`` and one speed term
  ``(s - 1/s) E`` per motor hold on every course and floor, however the load's share of the power
  changes with them; a resistance or gear efficiency apart changes the gain alone, which is why the
  two are fitted as two numbers. One gain table over power (the map before) can only be right for
  one mix of load and speed.
* **The fit.** The balance runs' errors (:func:`balance_errors`: each run's course error and its turn
  per metre) respond to motor i's power change ``dP_i`` as ``J_ri dP_i / a_ri`` (``J``: measured per
  log-gain at one power, reused at the others as the gain fit did); the change is
  ``(g_i - 1) a_ri + c_i u_ri``, linear in the gains and speed terms, so each step is one linear least
  squares over every power at once (:func:`model_step`), the gains' mean and the speed terms' sum held
  (a common factor is the K_l tables' business).
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
    speed: list[float] = field(default_factory=list)
    """Each motor's speed term, PWM counts per m/s (empty: none fitted)."""
    rates: list[tuple[float, int, float]] = field(default_factory=list)
    """(folded course, nominal power, rim speed m/s of the busiest wheel) of each balance run that moved."""

    def as_dict(self) -> dict[str, list[Any]]:
        """The outcome as plain data (for the JSON report)."""
        return {
            "powers": self.powers,
            "log_gains": self.log_gains,
            "speed": self.speed,
            "before": self.before,
            "after": self.after,
        }

    def rate(self, power: float, folded: float) -> float:
        """The busiest wheel's rim speed (m/s) that nominal ``power`` gave on the balance run course
        nearest ``folded``: linear in power between the runs' medians, through 0 below the lowest
        and along the last segment above the highest (0 without runs)."""
        if not self.rates:
            return 0.0
        course = min({c for c, _, _ in self.rates}, key=lambda c: abs(c - folded))
        by_power: dict[int, list[float]] = {}
        for c, p, v in self.rates:
            if c == course:
                by_power.setdefault(p, []).append(v)
        ps = sorted(by_power)
        vs = [statistics.median(by_power[p]) for p in ps]
        if power <= ps[0]:
            return max(vs[0] * power / ps[0], 0.0)
        if len(ps) == 1 or power <= ps[-1]:
            return float(np.interp(power, ps, vs))
        slope = (vs[-1] - vs[-2]) / (ps[-1] - ps[-2])
        return max(vs[-1] + slope * (power - ps[-1]), 0.0)

    def tables(self, n: int) -> tuple[PiecewiseLinear, ...]:
        """Each of ``n`` motors' gain table (exp of its log-gains per power); identity when nothing was
        fitted."""
        if not self.powers:
            return identity(n).gain
        if all(g == self.log_gains[0] for g in self.log_gains):  # the motor model: one gain each
            return tuple(PiecewiseLinear(x=(0.0,), y=(round(math.exp(v), 3),)) for v in self.log_gains[0])
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


SPEED_LIMIT = 0.5
"""abs(speed term) / K is kept below this (a motor's back-EMF at most half the whole K apart)."""
SPEED_RIDGE = 0.02
"""Weight that pulls the speed terms (in units of K) towards 0 where the runs cannot tell them."""


def model_step(
    jac: np.ndarray,
    e: np.ndarray,
    ratios: np.ndarray,
    x: np.ndarray,
) -> np.ndarray:
    """The motor model after one Gauss-Newton step on the errors ``e`` of the runs at ``x``.

    ``x`` is ``(g_1 - 1 .. g_n - 1, c_1 / K .. c_n / K)`` (gains and speed terms in units of K);
    ``jac`` (rows: errors, columns: motors) the errors' response per relative power change of each
    motor; ``ratios`` (rows as ``e``) each motor's ``K u / a`` in that run (0 where it does not drive).
    The error's response to ``x`` is ``jac`` for the gains and ``jac * ratios`` for the speed terms.
    Rows with a NaN are left out; the gains' sum and the speed terms' sum are held at 0, the speed
    terms pulled lightly towards 0 (:data:`SPEED_RIDGE`) and both clipped (:data:`GAIN_LIMIT`,
    :data:`SPEED_LIMIT`).
    """
    n = jac.shape[1]
    rows = np.isfinite(e) & np.all(np.isfinite(jac), axis=1) & np.all(np.isfinite(ratios), axis=1)
    a = np.hstack([jac[rows], jac[rows] * ratios[rows]])
    hold = np.zeros((2, 2 * n))
    hold[0, :n] = 1.0
    hold[1, n:] = 1.0
    ridge = np.hstack([np.zeros((n, n)), SPEED_RIDGE * np.eye(n)])
    lhs = np.vstack([a, 10.0 * hold, ridge])
    rhs = np.concatenate([-e[rows], -10.0 * np.array([x[:n].sum(), x[n:].sum()]), -SPEED_RIDGE * x[n:]])
    step = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
    out = x + step
    limit = math.exp(GAIN_LIMIT) - 1.0
    out[:n] = np.clip(out[:n], math.exp(-GAIN_LIMIT) - 1.0, limit)
    out[n:] = np.clip(out[n:], -SPEED_LIMIT, SPEED_LIMIT)
    return np.asarray(out)


def motor_model(offsets: Sequence[float], x: np.ndarray, k: float) -> MotorMapSpec:
    """A motor map with ``offsets``, one constant gain and one speed term per motor (``x`` as
    :func:`model_step`'s, K the calibration's PWM counts per m/s)."""
    n = len(offsets)
    gains = tuple(PiecewiseLinear(x=(0.0,), y=(round(1.0 + float(v), 3),)) for v in x[:n])
    return MotorMapSpec(offset=tuple(offsets), gain=gains, speed=tuple(round(float(v) * k, 1) for v in x[n:]))


def constant_gains(offsets: Sequence[float], x: np.ndarray) -> MotorMapSpec:
    """A motor map with ``offsets`` and one constant gain per motor, exp of ``x``."""
    gains = tuple(PiecewiseLinear(x=(0.0,), y=(float(math.exp(v)),)) for v in x)
    return MotorMapSpec(offset=tuple(offsets), gain=gains)


def rms(e: np.ndarray) -> float:
    """Root mean square of the finite values of ``e`` (inf when there are none)."""
    ok = e[np.isfinite(e)]
    return float(np.sqrt(np.mean(ok * ok))) if ok.size else math.inf
