"""Steady wheel slip of omni and mecanum wheels: a per-floor model for wheel odometry.

A driven wheel transmits force to the floor through a rubber (or carpet-pile) contact that creeps:
the rim turns a little faster than the ground moves, in the direction the wheel pushes. On a hard
floor that creep is small; on carpet the rollers of every wheel roll against a large rolling
resistance, the driven wheels must push against it all the time, and the encoders over-read by
several percent. The pattern is a rigid motion for most courses (each wheel's over-read matches
its share of the motion), so the fit residual and the gyro cannot see it: it has to be calibrated
once per floor and then subtracted.

The model, with five per-floor numbers::

    scale * encoder rim speed of wheel k  =  T_k q  +  roll * p_k(q)  +  combined * c_k(q)
                                                    +  compliance * a_k(q_dot)  +  ramp * p_k(q) |a|^2

* ``q`` the body twist, ``T_k`` the wheel's traction row (rim speed = r cos(gamma) omega);
* ``p_k``: the traction force wheel k needs, in units of one wheel's roller drag, so that the drive
  balances the rollers' rolling resistance ``-sum_j tanh(roll_j / eps) N_j`` (each roller row
  ``N_j`` resists its own rolling speed; least-norm over the wheels, as equal wheels share it);
* ``c_k`` (m/s): the same share of the rollers' combined rolling-and-driving drag,
  ``-sum_j sin(2 beta_j) roll_j N_j``, where ``sin(2 beta_j) = 2 |rim_j| |roll_j| / (rim_j^2 +
  roll_j^2)`` weighs how diagonally the contact crosses roller j (0 when the wheel or its rollers
  stand still, 1 at 45 degrees): a viscous loss while a wheel drives and its rollers roll at once,
  which makes the creep depend on the course (none on an omni4 axis, most at 45 degrees);
* ``a_k``: the traction force wheel k needs, per unit mass, to accelerate the body (m/s^2);
* ``|a|^2``: the body's squared acceleration along the floor ((m/s^2)^2). A tyre's creep grows
  faster than the force it transmits (the simulator's friction law: creep = v_eps atanh(F / F_max)),
  so while the body speeds up or brakes the drag's share creeps more than at a steady speed, by
  about ``(F_a / F_max)^2`` of it, ``F_a`` the ramp's force on the wheel: over a ramp up and down
  the odd powers of ``F_a`` cancel and this even one is left (omni3 on carpet, 30 kg on a grip of
  0.75: +21 % of the drag's creep at 1 m/s^2, fitted);
* ``roll`` (m/s), ``combined`` (dimensionless: m/s of creep per m/s of weighted roller speed),
  ``compliance`` (s) and ``ramp`` (s^3/m) are the floor's: the creep of a wheel carrying one roller
  drag, per unit of combined drag, per unit acceleration, and per roller drag and squared
  acceleration; ``scale`` is the tyres' rolling radius against the description's. :func:`fit_slip`
  fits them from straight runs with a known true displacement (the simulator's truth, or a tape
  measure).

:class:`SlipModel` gives the correction for a twist; :class:`~omnibot.estimation.estimator.PoseEstimator`
(``slip=``) scales the encoder increments and subtracts it before the least-squares forward
kinematics.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.errors import ConfigError
from omnibot.estimation.creep import SlipParameters, creep_rows
from omnibot.motion import Twist
from omnibot.robot import RobotDescription, kinematics

FloatArray = NDArray[np.float64]

ROLL_EPS = 0.01
"""m/s: rolling speed over which a roller's resistance builds up (the model's sign regularisation)."""


class SlipPatterns(NamedTuple):
    """Per-wheel force shares at one twist: of the roller drag (units of one drag), of the combined
    rolling-and-driving drag (m/s), of the acceleration (m/s^2), and of the roller drag while the body
    accelerates (the drag's share times the squared acceleration, (m/s^2)^2)."""

    roll: FloatArray
    combined: FloatArray
    accel: FloatArray
    ramp: FloatArray


class SlipModel:
    """The creep pattern of a robot's wheels (geometry from its description, coefficients per floor)."""

    def __init__(self, robot: RobotDescription, params: SlipParameters | None = None) -> None:
        rows = creep_rows(robot)
        self.rim_per_rad = np.array(rows.rim_per_rad)
        """m of rim travel along the traction direction per rad of wheel turn."""
        self.roll_rows = np.array(rows.roll)
        """Each wheel's roller rolling speed over the body twist (with the body and, on mecanum
        wheels, with the wheel's own turn)."""
        self.rim_rows = np.array(rows.rim)
        """Each wheel's rim speed r omega over the body twist (rolling without slip)."""
        self._share = np.array(rows.share)  # (m, 3): least-norm wheel forces for a body wrench
        self._roller_wrench = kinematics.robot_contact_rows(robot)[1]  # wheel k's roller drag as a wrench row
        self.mix = np.array(rows.mix)
        """(m, m): wheel k's over-turn (rad/s) per m/s of creep term of roller row j (the firmware's
        ``creep_mix``: ``creep = roll p + combined c`` in rad/s of each wheel)."""
        self.inertia_ratio = robot.yaw_inertia / robot.mass
        self.params = params or SlipParameters()
        self._wheel_twist = kinematics.forward_matrix(robot)
        """The least-squares body twist of wheel speeds (rad/s)."""

    def patterns(self, twist: ArrayLike, accel: ArrayLike = (0.0, 0.0, 0.0)) -> SlipPatterns:
        """The per-wheel force shares of the roller drag, the combined drag and the acceleration."""
        q = np.asarray(twist, dtype=float)
        rolling = self.roll_rows @ q
        rim = self.rim_rows @ q
        both = rim * rim + rolling * rolling
        sin2beta = np.divide(
            2.0 * np.abs(rim) * np.abs(rolling), both, out=np.zeros_like(both), where=both > 1e-12
        )
        p = self._share @ (self._roller_wrench.T @ np.tanh(rolling / ROLL_EPS))
        c = self._share @ (self._roller_wrench.T @ (sin2beta * rolling))
        acc = np.asarray(accel, dtype=float)
        a = self._share @ np.array([acc[0], acc[1], self.inertia_ratio * acc[2]])
        return SlipPatterns(p, c, a, p * float(acc[0] * acc[0] + acc[1] * acc[1]))

    def creep(self, twist: ArrayLike, accel: ArrayLike = (0.0, 0.0, 0.0)) -> FloatArray:
        """Per-wheel rim over-speed (m/s) at body twist ``twist`` and body acceleration ``accel``."""
        p, c, a, r = self.patterns(twist, accel)
        par = self.params
        creep: FloatArray = par.roll * p + par.combined * c + par.compliance * a + par.ramp * r
        return creep

    def wheel_correction(self, twist: ArrayLike, accel: ArrayLike = (0.0, 0.0, 0.0)) -> FloatArray:
        """Per-wheel over-turn (rad/s) to subtract from measured wheel speeds."""
        turn: FloatArray = self.creep(twist, accel) / self.rim_per_rad
        return turn

    def commanded(self, twist: Twist, accel: ArrayLike = (0.0, 0.0, 0.0)) -> Twist:
        """The twist to ask a wheel-speed loop for so that the body goes at ``twist`` on this floor:
        the loop holds the encoders at the asked twist's wheel speeds, which the creep over-reads, so
        each wheel is asked for its creep on top and the tyres' scale taken out, ``(q + J^+
        correction(q, a)) / scale``, the least-squares twist of those wheel speeds (the creep of most
        courses is a rigid motion: its least-squares twist is exact). ``accel``: the body's planned
        acceleration ``a`` (m/s^2 along its axes, rad/s^2), whose force the tyres creep under too
        (``compliance``): asked for while the body accelerates, it keeps the body on the plan instead
        of behind its wheels."""
        q = np.array([twist.vx, twist.vy, twist.w])
        out = (q + self._wheel_twist @ self.wheel_correction(q, accel)) / self.params.scale
        return Twist(float(out[0]), float(out[1]), float(out[2]))


@dataclass(frozen=True)
class SlipLeg:
    """One calibration run: the body twists the encoders saw and the true displacement.

    ``twists`` (n, 3) and ``accels`` (n, 3) are body-frame samples ``dt`` (n,) s long each, from the
    encoders (uncorrected) and the gyro, ``headings`` (n,) the estimated heading at each; and
    ``encoder_disp`` and ``true_disp`` are the (x, y) displacements over the run in the estimator's
    (world) frame, by the encoders and by the truth.
    """

    twists: FloatArray
    accels: FloatArray
    dt: FloatArray
    headings: FloatArray
    encoder_disp: tuple[float, float]
    true_disp: tuple[float, float]


SCALE_EXPLAINS = 0.5
"""A fitted distance scale must leave less than this fraction of the squared error the creep terms
leave alone. Measured on omni4 on carpet: a scale of 0.988 that took out 23 % of it made the
estimate 1.2 % short on every metre (the standard square: 2.4 cm RMS against 0.75 with the scale
at 1); on synthetic runs with a 4 % radius error the scale takes out all but 1e-28 of it."""

CREEP_COLUMNS = ("roll", "combined", "compliance", "ramp")
"""The creep coefficients, in the order of :func:`_regressors`' columns."""


def _regressors(model: SlipModel, J_pinv: FloatArray, leg: SlipLeg) -> FloatArray:
    """(2, 4): d(encoder - true displacement, estimator frame) / d(roll, combined, compliance, ramp)."""
    out = np.zeros((2, len(CREEP_COLUMNS)))
    for q, acc, dt, th in zip(leg.twists, leg.accels, leg.dt, leg.headings, strict=True):
        patterns = model.patterns(q, acc)
        c, s = math.cos(th), math.sin(th)
        for col, pattern in enumerate(patterns):
            body = J_pinv @ (pattern / model.rim_per_rad) * dt
            out[0, col] += c * body[0] - s * body[1]
            out[1, col] += s * body[0] + c * body[1]
    return out


def fit_slip(
    robot: RobotDescription,
    legs: Sequence[SlipLeg],
    compliance: bool = False,
    scale: bool = False,
    combined: bool = True,
    ramp: bool = False,
) -> SlipParameters:
    """Least-squares creep coefficients from runs with known true displacements.

    Each leg contributes two equations (x and y of encoder minus true displacement); the creep
    coefficients are kept non-negative (creep is in the direction a wheel pushes: a negative one is
    noise, so that term is dropped and the rest refitted). ``compliance`` also fits the acceleration
    term: over a run from rest to rest its creep integrates to almost nothing (the wheels creep
    forward while speeding up and back while braking), so it needs runs measured while moving.
    ``combined`` fits the combined-drag term (it needs runs on courses that cross the rollers at
    different angles, as the evenly spaced courses do: on omni4 it is 0 on the axes and largest at
    45 degrees). ``ramp`` fits the drag's extra creep under acceleration (it needs runs whose ramps
    differ: from rest to rest a steady drag's creep grows with the time taken, the ramp's with the
    time spent accelerating times the acceleration squared). ``scale`` also fits the encoders'
    distance scale: it needs runs at two speeds (a radius error grows with the distance, the
    rolling creep with the time taken). The combined term, the ramp term and the scale are each
    kept only when they explain the runs better by more than an extra parameter's worth (the
    Bayesian information criterion ``n ln(cost) + k ln(n)`` over the n equations, k the extra
    terms); otherwise they stay 0 (the scale 1), as they would only trade against the rest. The
    scale must also take out at least half of what the creep terms leave
    (:data:`SCALE_EXPLAINS`): a real radius error is on every run in proportion to its distance
    and dominates the rest, while a scale that takes out a part only stands in for the creep
    model's mismatch and, unlike it, grows with every metre driven.
    """
    if not legs:
        raise ConfigError("a slip fit needs at least one run")
    model = SlipModel(robot)
    J_pinv = kinematics.forward_matrix(robot)
    rows, rhs = [], []
    for leg in legs:
        rows.append(np.column_stack((_regressors(model, J_pinv, leg), leg.encoder_disp)))
        rhs.append(np.subtract(leg.encoder_disp, leg.true_disp))
    A = np.vstack(rows)  # columns: roll, combined, compliance, ramp, 1 - scale
    b = np.concatenate(rhs)
    n = len(b)
    best, best_score = SlipParameters(), math.inf
    options = itertools.product((False, True) if combined else (False,), (False, True) if ramp else (False,))
    for with_combined, with_ramp in options:
        creep = [col for col, on in enumerate((True, with_combined, compliance, with_ramp)) if on]
        fits = [(*_fit_creep(A, b, creep, free=[]), False)]
        if scale:
            scaled, scaled_cost = _fit_creep(A, b, creep, free=[4])
            if scaled_cost < SCALE_EXPLAINS * fits[0][1]:
                fits.append((scaled, scaled_cost, True))
        for params, cost, with_scale in fits:
            extra = with_combined + with_ramp + with_scale
            score = n * math.log(max(cost, 1e-30)) + extra * math.log(n)
            if score < best_score:
                best, best_score = params, score
    return best


def _fit_creep(
    A: FloatArray, b: FloatArray, creep: list[int], free: list[int]
) -> tuple[SlipParameters, float]:
    """The best fit with a subset of the ``creep`` columns, non-negative, and the ``free`` columns
    unconstrained."""
    best, best_cost = SlipParameters(), math.inf
    for size in range(len(creep), -1, -1):
        for subset in itertools.combinations(creep, size):
            cols = [*subset, *free]
            coef = np.linalg.lstsq(A[:, cols], b, rcond=None)[0] if cols else np.zeros(0)
            if np.any(coef[:size] < 0):
                continue
            x = np.zeros(A.shape[1])
            x[cols] = coef
            residual = b - A @ x
            cost = float(residual @ residual)
            if cost < best_cost:
                roll, comb, compl, ramp, shrink = (float(v) for v in x)
                best, best_cost = SlipParameters(roll, compl, 1.0 - shrink, comb, ramp), cost
    return best, best_cost


def leg_residual(
    leg: SlipLeg, params: SlipParameters | None = None, robot: RobotDescription | None = None
) -> FloatArray:
    """(x, y) m: encoder - true displacement of a run (estimator frame), uncorrected or with
    ``params`` taken out (``robot`` is then needed for the geometry)."""
    err = np.subtract(leg.encoder_disp, leg.true_disp)
    if params is not None:
        if robot is None:
            raise ValueError("leg_residual needs the robot to apply slip parameters")
        reg = _regressors(SlipModel(robot), kinematics.forward_matrix(robot), leg)
        err = (
            err
            - reg @ np.array([params.roll, params.combined, params.compliance, params.ramp])
            - (1.0 - params.scale) * np.asarray(leg.encoder_disp)
        )
    residual: FloatArray = err
    return residual


def leg_error(
    leg: SlipLeg, params: SlipParameters | None = None, robot: RobotDescription | None = None
) -> float:
    """|encoder - true displacement| / true distance of a run, uncorrected or with ``params``
    (``robot`` is then needed for the geometry)."""
    err = leg_residual(leg, params, robot)
    return float(np.hypot(*err) / max(float(np.hypot(*leg.true_disp)), 1e-9))
