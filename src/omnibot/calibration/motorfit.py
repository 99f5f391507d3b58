"""The motor map, fitted: each motor's dead-band offset and its two-number motor model (pure
functions, no I/O; :mod:`omnibot.calibration.motors` drives the runs).

The firmware gives motor i ``sign(a) (offset_i + gain_i(|a|) |a|) + speed_i u_i`` for the nominal
power ``a`` of the calibration factors and the wheel's rim speed ``u_i`` (docs/firmware.md);
:func:`omnibot.calibration.patterns.map_power` is the same on the host.

* **Offsets.** ``offset_i = deadband_i * rotation / mean(deadband)`` (:func:`offsets_from_deadbands`):
  each motor's dead band alone, scaled so that their mean is the dead band of rotation in place.
* **The motor model.** A DC motor through its driver needs ``P = R tau / (eta k G) + k G omega``
  (in PWM counts: the load's torque through the winding's resistance, and the back-EMF). Where the
  nominal motor needs ``a = a_load + E u`` (E: the nominal back-EMF in counts per m/s of rim speed,
  :func:`emf_counts`), a motor with ``s`` times its torque constant and ``r`` times its load factor
  (resistance over gear efficiency) needs ``r a_load / s + s E u = g a + (s - g) E u`` with
  ``g = r / s``: a gain and a speed term ``(s - g) E`` per motor, right on every course and floor
  however the load's share of the power changes with them.
* **Why the floor alone cannot tell the two apart.** A speed term c acts in a run as the gain
  ``g + (c / K) rho`` with ``rho = K u / a``; the balance runs' errors see only that sum. rho comes
  from the load's share of the power: on wood it stays at 0.7-1.3 (the 45 degree courses lowest),
  on carpet 0.1-0.9, and where it varies most (near the dead band, or where the drivers limit the
  current) the runs are erratic or no map balances them. A fit of both numbers per motor on the
  acceptance robot's balance runs has a Fisher information of condition number 1.8e4 on carpet and
  4.5e4 on wood (:func:`floor_information`, docs/calibration.md): the data fix one combination per
  motor, not two.
* **The stand test** (:func:`stand_torque`) measures the torque constants where the load is known:
  the robot lifted, each free wheel's speed at three powers; the slope gives s (the back-EMF) through
  the description's friction, the common share (the bus voltage under load) set so that their
  geometric mean is 1. The balance runs then fit one gain per motor with its speed term tied to it,
  ``(s - g) E`` (:func:`gain_rows`, :func:`gain_fit_step`: Gauss-Newton over every power at once,
  well conditioned), on each run's course error and turn per metre (:func:`balance_errors`).
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
from omnibot.robot import MotorMapSpec, PiecewiseLinear, RobotDescription

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
    """Raw courses (degrees) of the balance runs: each ``folded`` course from every idle axis, both
    ways (default: the idle axes and halfway between two)."""
    axes = sorted(a % 180.0 for a in geometry.idle_axes)
    out: list[float] = []
    for a in axes:
        for f in folded if folded is not None else (0.0, geometry.idle_fold_max):
            c = a + f
            out += [round(c % 360.0, 6), round((c + 180.0) % 360.0, 6)]
    return sorted(set(out))


@dataclass(frozen=True)
class Information:
    """How well the balance runs tell the gains apart: the Fisher information of the linearised fit,
    the common share the fit holds taken out."""

    condition: float
    """Largest over smallest eigenvalue (inf: some combination is not measured at all)."""
    stderr: tuple[float, ...]
    """Standard error of each gain at the fit's residual scatter."""


@dataclass(frozen=True)
class Stand:
    """The stand test: each motor's free wheel speed at a few powers, and the torque constants."""

    powers: tuple[float, ...]
    speeds: tuple[tuple[float, ...], ...]
    """rad/s, per power, per motor."""
    torque: tuple[float, ...]
    """Each motor's torque constant against the description's."""
    stderr: tuple[float, ...]
    """Standard error of each (from the slope's scatter over the powers)."""
    bus: float
    """The bus voltage on the stand against the described one, as the common share came out."""

    def as_dict(self) -> dict[str, Any]:
        """The stand test as plain data (for the JSON report)."""
        return {
            "powers": list(self.powers),
            "speeds": [list(r) for r in self.speeds],
            "torque": list(self.torque),
            "stderr": list(self.stderr),
            "bus": self.bus,
        }


@dataclass
class Balance:
    """The balance runs' outcome: the gain table of each motor and the errors before and after."""

    powers: list[int] = field(default_factory=list)
    log_gains: list[list[float]] = field(default_factory=list)
    """Per power, each motor's log-gain (one gain per motor: the same at every power)."""
    before: list[float] = field(default_factory=list)
    """Per power, the rms error (rad) through the offsets alone."""
    after: list[float] = field(default_factory=list)
    """Per power, the rms error (rad) through the fitted map."""
    speed: list[float] = field(default_factory=list)
    """Each motor's speed term, PWM counts per m/s (empty: none fitted)."""
    torque: list[float] = field(default_factory=list)
    """Each motor's torque constant against the nominal one, from the stand test (empty: not run)."""
    information: Information | None = None
    """How well the runs told the gains apart (None: nothing fitted)."""
    floor_only: Information | None = None
    """How well the same runs would tell both numbers per motor apart without the stand (None: nothing
    fitted)."""
    stand: Stand | None = None
    """The stand test the speed terms come from (None: not run, the speed terms 0)."""
    rates: list[tuple[float, int, float]] = field(default_factory=list)
    """(folded course, nominal power, rim speed m/s of the busiest wheel) of each balance run that moved."""

    def as_dict(self) -> dict[str, Any]:
        """The outcome as plain data (for the JSON report)."""
        return {
            "powers": self.powers,
            "log_gains": self.log_gains,
            "speed": self.speed,
            "torque": self.torque,
            "condition": None if self.information is None else self.information.condition,
            "stderr": None if self.information is None else list(self.information.stderr),
            "floor_only_condition": None if self.floor_only is None else self.floor_only.condition,
            "stand": None if self.stand is None else self.stand.as_dict(),
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


GAIN_RIDGE = 0.05
"""Weight (per unit of gain, against the heaviest error row's 1) that holds each gain lightly at
``1 / s`` where the runs cannot tell it."""
COMMON = 10.0
"""Weight of the row that holds the gains' common share (the K_l tables')."""
ERROR_FLOOR = 0.02
"""rad (and rad per metre): a power's rms error below this counts as this in its weight (the runs'
scatter)."""


def emf_counts(robot: RobotDescription) -> tuple[float, ...]:
    """Each motor's nominal back-EMF E in PWM counts per m/s of its wheel's rim speed:
    ``pwm_max k G / (r (V - V_drop))`` from the description (battery voltage without sag)."""
    out = []
    for w in robot.wheels:
        m = w.motor
        volts = max(robot.battery.voltage - m.driver_drop, 0.1 * robot.battery.voltage)
        out.append(m.pwm_max * m.torque_constant * m.gear_ratio / (w.radius * volts))
    return tuple(out)


def gain_rows(jac: np.ndarray, ratios: np.ndarray, emf: np.ndarray, k: float) -> np.ndarray:
    """The errors' response to each motor's gain when its speed term is ``(s - g) E`` (``emf``: E per
    motor; ``ratios``: ``K u / a`` per error row and motor, 0 where it does not drive).

    In a run where motor i's nominal power is ``a`` and its rim speed ``u``, gain g and speed term
    ``c = (s - g) E`` give it ``g a + (s - g) E u``: it acts as the gain
    ``g (1 - E u / a) + s E u / a``, whose slope in g is ``1 - (E / K) rho`` with ``rho = K u / a``;
    the errors respond to that gain as ``jac`` (per unit of gain: the finite-difference Jacobian of
    the run's power). With the torque constants unknown (no stand) pass ``emf`` 0: the gains alone."""
    return np.asarray(jac * (1.0 - ratios * (emf / k)[None, :]))


def gain_fit_step(
    rows: np.ndarray, e: np.ndarray, weights: np.ndarray, torque: np.ndarray, ridge: float = GAIN_RIDGE
) -> np.ndarray:
    """The gains g that zero ``e + rows g`` best (``rows``: :func:`gain_rows`; ``e``: the errors
    extrapolated to all gains 0 along them, :func:`gain_origin`; rows weighted by ``weights``):
    ``sum(torque * g)`` held at n (the motors' load factors, resistance over gear efficiency, average
    the nominal: a common share is the K_l tables'), held lightly at ``1 / torque`` (``ridge``: the
    motor that differs in its torque constant alone), clipped to :data:`GAIN_LIMIT`; rows with a NaN
    are left out."""
    n = torque.size
    ok = np.isfinite(e) & np.all(np.isfinite(rows), axis=1)
    weights = weights / max(float(np.max(weights[ok])), 1e-300) if ok.any() else weights
    lhs = np.vstack([weights[ok, None] * rows[ok], COMMON * torque[None, :], ridge * np.eye(n)])
    rhs = np.concatenate([-weights[ok] * e[ok], [COMMON * n], ridge / torque])
    out = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
    return np.asarray(np.clip(out, math.exp(-GAIN_LIMIT), math.exp(GAIN_LIMIT)))


def effective_gains(gains: np.ndarray, speed: np.ndarray, ratios: np.ndarray, k: float) -> np.ndarray:
    """The gain each motor acts with in each error row's run: ``g + (c / K) rho`` (``ratios``: rho =
    ``K u / a``, 0 where it does not drive)."""
    return np.asarray(gains[None, :] + (speed / k)[None, :] * ratios)


def gain_origin(
    e: np.ndarray,
    jac: np.ndarray,
    acted: np.ndarray,
    ratios: np.ndarray,
    torque: np.ndarray,
    emf: np.ndarray,
    k: float,
) -> np.ndarray:
    """The errors ``e`` of runs whose motors acted with the gains ``acted`` (:func:`effective_gains`),
    extrapolated along the Jacobian ``jac`` to the model's gains 0 with speed terms ``s E``: the
    constant part of the linear model that :func:`gain_fit_step` zeroes with ``gain_rows``."""
    return np.asarray(e + np.sum(jac * (ratios * (torque * emf / k)[None, :] - acted), axis=1))


STAND_POWERS = (0.4, 0.65, 0.9)
"""The stand test's powers, fractions of pwm_max (well above a free wheel's dead band)."""


def stand_torque(
    robot: RobotDescription, powers: Sequence[float], speeds: Sequence[Sequence[float]]
) -> Stand:
    """Each motor's torque constant (times the description's) from its free wheel's steady speed
    (rad/s, ``speeds[j][i]`` for motor i at PWM ``powers[j]``) on the stand.

    A free wheel's motor needs ``lambda V P / P_max = s k G omega + R (tau_c + b omega) / (eta s k G)``
    (back-EMF, and the current its own friction draws; V the description's battery less the driver's
    drop): the slope ``d omega / d P`` (least squares over the powers) gives ``k G s^2 - X s + R b /
    (eta k G) = 0`` with ``X = lambda V / (P_max slope)``, solved for s (the description's k, G, R,
    b, eta). ``lambda``, the bus voltage against the described one (the battery's sag under the
    four motors' current, the driver's drop), is common to all motors and so is the torque
    constants' common share, which only the K_l tables see: it is chosen so that their geometric
    mean is 1. The slope's standard error gives each s's."""
    p = np.asarray(powers, dtype=float)
    slopes, ses = [], []
    for i in range(robot.n_wheels):
        w = np.asarray([row[i] for row in speeds], dtype=float)
        coef, res, *_ = np.polyfit(p, w, 1, full=True)
        dof = max(p.size - 2, 1)
        slopes.append(float(coef[0]))
        ses.append(math.sqrt(float(res[0]) / dof / float(np.sum((p - p.mean()) ** 2))) if res.size else 0.0)

    def solve(i: int, slope: float, scale: float) -> float:
        m = robot.wheels[i].motor
        volts = max(robot.battery.voltage - m.driver_drop, 0.1 * robot.battery.voltage)
        kg = m.torque_constant * m.gear_ratio
        visc = m.resistance * m.friction_viscous / (m.gear_efficiency * kg)
        if slope <= 0.0:
            return math.nan
        x = scale * volts / (m.pwm_max * slope)
        return (x + math.sqrt(max(x * x - 4.0 * kg * visc, 0.0))) / (2.0 * kg)

    def log_mean(scale: float) -> float:
        return float(np.mean([math.log(solve(i, sl, scale)) for i, sl in enumerate(slopes)]))

    lo, hi = 0.2, 5.0
    if not all(sl > 0.0 for sl in slopes):
        return Stand(
            tuple(p.tolist()), _rows(speeds), (math.nan,) * len(slopes), (math.nan,) * len(slopes), math.nan
        )
    for _ in range(60):  # log_mean rises with the scale
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if log_mean(mid) < 0.0 else (lo, mid)
    scale = math.sqrt(lo * hi)
    torque = tuple(solve(i, sl, scale) for i, sl in enumerate(slopes))
    stderr = tuple(
        abs(solve(i, sl - se, scale) - t) if se > 0.0 else 0.0
        for i, (sl, se, t) in enumerate(zip(slopes, ses, torque, strict=True))
    )
    return Stand(tuple(p.tolist()), _rows(speeds), torque, stderr, scale)


def _rows(speeds: Sequence[Sequence[float]]) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(float(v) for v in row) for row in speeds)


def information(rows: np.ndarray, weights: np.ndarray, scatter: float, held: np.ndarray) -> Information:
    """The Fisher information ``rows^T W rows`` of the weighted rows on the parameters less the
    directions ``held`` (a vector, or one column per direction: the common shares the fit holds), its
    condition number, and the parameters' standard errors at a residual scatter ``scatter`` (rms of
    the weighted residuals)."""
    ok = np.all(np.isfinite(rows), axis=1) & np.isfinite(weights)
    a = weights[ok, None] * rows[ok]
    n = rows.shape[1]
    h = held.reshape(n, -1)
    q = np.linalg.svd(h, full_matrices=True)[0][:, h.shape[1] :]  # the complement of the held shares
    f = q.T @ (a.T @ a) @ q
    eig = np.linalg.eigvalsh(f)
    if eig[0] <= 1e-12 * max(eig[-1], 1e-300):
        return Information(math.inf, (math.inf,) * n)
    cov = scatter * scatter * (q @ np.linalg.inv(f) @ q.T)
    return Information(float(eig[-1] / eig[0]), tuple(float(math.sqrt(max(v, 0.0))) for v in np.diag(cov)))


def floor_information(
    jac: np.ndarray, ratios: np.ndarray, weights: np.ndarray, scatter: float
) -> Information:
    """How well balance runs alone would tell both numbers per motor apart (no stand): the
    :func:`information` of the gains and speed terms / K, which act in a run as ``g + (c / K) rho``
    (rows ``[J, J rho]``), their two common shares held."""
    n = jac.shape[1]
    held = np.zeros((2 * n, 2))
    held[:n, 0] = held[n:, 1] = 1.0
    return information(np.hstack([jac, jac * ratios]), weights, scatter, held)


def model_map(offsets: Sequence[float], gains: np.ndarray, speed: np.ndarray) -> MotorMapSpec:
    """The motor map of ``offsets``, one constant gain and one speed term (counts per m/s) per motor."""
    tables = tuple(PiecewiseLinear(x=(0.0,), y=(float(g),)) for g in gains)
    return MotorMapSpec(offset=tuple(offsets), gain=tables, speed=tuple(float(c) for c in speed))


def constant_gains(offsets: Sequence[float], x: np.ndarray) -> MotorMapSpec:
    """A motor map with ``offsets`` and one constant gain per motor, exp of ``x``."""
    gains = tuple(PiecewiseLinear(x=(0.0,), y=(float(math.exp(v)),)) for v in x)
    return MotorMapSpec(offset=tuple(offsets), gain=gains)


def rms(e: np.ndarray) -> float:
    """Root mean square of the finite values of ``e`` (inf when there are none)."""
    ok = e[np.isfinite(e)]
    return float(np.sqrt(np.mean(ok * ok))) if ok.size else math.inf
