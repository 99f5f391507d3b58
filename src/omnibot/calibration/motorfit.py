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
  back-EMF in counts per m/s of rim speed, :func:`emf_counts`). One gain ``1/s`` and one speed term
  ``(s - 1/s) E`` per motor hold on every course and floor, however the load's share of the power
  changes with them; a resistance or gear efficiency apart changes the gain alone, which is why the
  two are two numbers. One gain table over power (the map before) can only be right for one mix of
  load and speed.
* **Gains** at each power: the Gauss-Newton step on the log-gains, their sum held at zero
  (:func:`gain_step`), on the balance runs' errors (:func:`balance_errors`: each run's course error
  and its turn per metre).
* **Speed terms** from what the gains left over: a speed term changes a motor's power in a run by
  ``(c / K) (K u / a)`` relative; with the gains re-centred at each power only the runs' departure
  from the power's mean ``K u / a`` counts (:func:`centred_ratios`), and one linear least squares
  over every power gives them (:func:`speed_step`). :func:`torque_of` is the torque constant a
  speed term implies for a motor that differs in its torque constant alone.
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
from omnibot.robot.description import MotorMapSpec, PiecewiseLinear, RobotDescription

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
    torque: list[float] = field(default_factory=list)
    """Each motor's torque constant against the nominal one, as its speed term implies
    (:func:`torque_of`; empty: none fitted)."""
    after_speed: list[float] = field(default_factory=list)
    """Per power, the rms error (rad) with the gains and speed terms (empty: the speed terms not kept)."""
    rates: list[tuple[float, int, float]] = field(default_factory=list)
    """(folded course, nominal power, rim speed m/s of the busiest wheel) of each balance run that moved."""

    def as_dict(self) -> dict[str, list[Any]]:
        """The outcome as plain data (for the JSON report)."""
        return {
            "powers": self.powers,
            "log_gains": self.log_gains,
            "speed": self.speed,
            "torque": self.torque,
            "after_speed": self.after_speed,
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


SPEED_RIDGE = 0.05
"""Weight (per unit of speed term / K) that holds the speed terms at 0 where the runs cannot tell them
(a light floor, whose courses load the motors alike)."""
SPEED_LIMIT = 0.5
"""abs(speed term) / K is kept below this."""
SPEED_KEEP = 0.75
"""The speed terms are kept only when the balance runs through them have at most this fraction of the
weighted rms error of the gains alone: a clear improvement, not a fit to the runs' scatter (on the
acceptance robot they were fitted with signs against its motors' when kept on any improvement)."""


def emf_counts(robot: RobotDescription) -> tuple[float, ...]:
    """Each motor's nominal back-EMF E in PWM counts per m/s of its wheel's rim speed:
    ``pwm_max k G / (r (V - V_drop))`` from the description (battery voltage without sag)."""
    out = []
    for w in robot.wheels:
        m = w.motor
        volts = max(robot.battery.voltage - m.driver_drop, 0.1 * robot.battery.voltage)
        out.append(m.pwm_max * m.torque_constant * m.gear_ratio / (w.radius * volts))
    return tuple(out)


def torque_of(speed: float, emf: float) -> float:
    """The torque constant (times the nominal) that a speed term implies for a motor that differs from
    the nominal one in its torque constant alone: ``speed = (s - 1/s) E`` solved for s."""
    q = speed / emf
    return (q + math.sqrt(q * q + 4.0)) / 2.0


def gain_step(jac: np.ndarray, e: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The log-gains after one Gauss-Newton step on the errors ``e`` (Jacobian ``jac``), their sum
    held at 0, clipped to :data:`GAIN_LIMIT`; rows with a NaN are left out."""
    n = x.size
    rows = np.isfinite(e) & np.all(np.isfinite(jac), axis=1)
    a = np.vstack([jac[rows], np.ones((1, n))])  # the last row holds the sum of log-gains at 0
    step = np.linalg.lstsq(a, -np.concatenate([e[rows], [x.sum()]]), rcond=None)[0]
    return np.asarray(np.clip(x + step, -GAIN_LIMIT, GAIN_LIMIT))


def centred_ratios(ratios: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each motor's ``K u / a`` less its mean over the runs it drives in (0 where it does not drive),
    and those means."""
    drives = ratios > 0.0
    counts = np.maximum(drives.sum(axis=0), 1)
    mean = np.where(drives, ratios, 0.0).sum(axis=0) / counts
    return np.where(drives, ratios - mean[None, :], 0.0), mean


def speed_step(jac: np.ndarray, e: np.ndarray, centred: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Speed terms / K that zero the errors ``e`` best (rows weighted by ``weights``).

    With gains re-centred at each power, a speed term c changes motor i's power in a run by
    ``(c_i / K) (K u / a - its mean at that power)`` relative (``centred``), to which the errors
    respond as ``jac`` (per relative power, rows as ``e``): one linear least squares, the sum held at
    0 (a common share is the K_l tables'), held lightly at 0 (:data:`SPEED_RIDGE`), clipped to
    :data:`SPEED_LIMIT`; rows with a NaN are left out.
    """
    n = jac.shape[1]
    rows = np.isfinite(e) & np.all(np.isfinite(jac), axis=1)
    a = weights[rows, None] * jac[rows] * centred[rows]
    lhs = np.vstack([a, 10.0 * np.ones((1, n)), SPEED_RIDGE * np.eye(n)])
    rhs = np.concatenate([-weights[rows] * e[rows], np.zeros(1 + n)])
    c = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
    return np.asarray(np.clip(c, -SPEED_LIMIT, SPEED_LIMIT))


def constant_gains(offsets: Sequence[float], x: np.ndarray) -> MotorMapSpec:
    """A motor map with ``offsets`` and one constant gain per motor, exp of ``x``."""
    gains = tuple(PiecewiseLinear(x=(0.0,), y=(float(math.exp(v)),)) for v in x)
    return MotorMapSpec(offset=tuple(offsets), gain=gains)


def rms(e: np.ndarray) -> float:
    """Root mean square of the finite values of ``e`` (inf when there are none)."""
    ok = e[np.isfinite(e)]
    return float(np.sqrt(np.mean(ok * ok))) if ok.size else math.inf
