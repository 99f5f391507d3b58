"""The motor map, measured: each motor's dead band alone and the balance runs (the fit is
:mod:`omnibot.calibration.motorfit`).

The firmware gives motor i ``sign(a) (offset_i + gain_i(|a|) |a|) + speed_i u_i`` for the nominal
power ``a`` of the calibration factors at the wheel's rim speed ``u_i`` (docs/firmware.md);
:func:`~omnibot.calibration.patterns.map_power` is the same on the host, so the sweeps' raw POWER
patterns drive the robot as the firmware will.

* **Offsets.** A motor's Coulomb friction needs a fixed power before its wheel turns at all; below
  it a slowly turning wheel (the side pair of an omni4 on course 15) stands still and the robot
  leaves its course. Each motor's dead band is found alone (:func:`motor_deadbands`: that motor's
  POWER only; its wheel also pushes the robot, so the number is a little high) and scaled so that
  their mean is the dead band of rotation in place, where no idle roller drags:
  ``offset_i = deadband_i * rotation / mean(deadband)``.
* **Gains and speed terms** (the two-number motor model, :mod:`~omnibot.calibration.motorfit`).
  Unequal motors turn the body on a straight run and pull it off its course. At a few nominal
  powers the balance runs drive every idle axis and the course halfway between two of them, both
  ways; the errors are each run's course error and its turn per metre, and each run's speed is
  measured too (its rim speeds are what the speed terms multiply). The log-gains (their sum held at
  zero: a common factor is the K_l tables' business) are found at each power by Gauss-Newton with a
  finite-difference Jacobian at the first power that moves the robot, reused (chord method) at the
  others, a step kept only when it lowers the rms error. Measuring the Jacobian again at every
  power, and Broyden updates of it, were tried: on carpet the steps then went astray (the
  acceptance check's carpet mean rose from 2.8 % to 6.7 and 4.8 %). The speed terms then come from
  what the gains left over (:func:`balance_model`); a joint Gauss-Newton of both numbers per motor
  over every power was tried and wandered off on wood (docs/calibration.md).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from omnibot.calibration.experiments import MOVED_ANGLE, MOVED_DISTANCE, Runner, lowest_moving
from omnibot.calibration.motorfit import (
    GAIN_STEP,
    SPEED_KEEP,
    Balance,
    balance_courses,
    balance_errors,
    centred_ratios,
    constant_gains,
    emf_counts,
    gain_step,
    rms,
    speed_step,
    torque_of,
)
from omnibot.calibration.patterns import Geometry, apply_map
from omnibot.calibration.runs import STRAIGHT, RunInfo
from omnibot.robot.description import MotorMapSpec


def motor_deadbands(runner: Runner, step: int = 8, duration: float = 0.5) -> list[int]:
    """Each motor's dead band alone: the lowest POWER on that motor only that moves the robot."""
    geo = runner.geometry
    out = []
    for i in range(geo.motors):
        flip = [1]

        def attempt(power: int, i: int = i, flip: list[int] = flip) -> bool:
            flip[0] = -flip[0]
            pattern = [0] * geo.motors
            pattern[i] = flip[0] * power
            info = RunInfo(STRAIGHT, f"dead band, motor {i + 1} alone, power {flip[0] * power}")
            runner.note(f"dead band motor {i + 1}: {power}")
            r = runner.power_run(pattern, duration, info, f"deadband:motor{i + 1}", power=power)
            m = r.truth
            if m is None:
                return False
            d, th = m.distance, m.theta
            return (d is not None and d >= MOVED_DISTANCE) or (th is not None and abs(th) >= MOVED_ANGLE)

        out.append(lowest_moving(attempt, step, geo.pwm_max))
    return out


def _errors(
    runner: Runner,
    courses: Sequence[float],
    power: int,
    motors: MotorMapSpec,
    duration: float,
    speeds: Sequence[float] | None = None,
) -> tuple[np.ndarray, list[float]]:
    """Course error (rad) and turn (rad per metre of path) of a run on each course (NaN where the
    robot hardly moved or the truth cannot tell), and each run's speed along its path (m/s, NaN where
    unknown). ``speeds``: the busiest wheel's rim speed each run is taken to reach, for the map's
    speed terms (none: 0)."""
    geo = runner.geometry
    out: list[float] = []
    moved: list[float] = []
    for k, c in enumerate(courses):
        rims = geo.translation_rim(c)
        peak = max(abs(v) for v in rims)
        u = speeds[k] if speeds is not None and math.isfinite(speeds[k]) else 0.0
        pattern = apply_map(
            motors, [power * v / peak for v in rims], geo.pwm_max, [u * v / peak for v in rims]
        )
        info = RunInfo(STRAIGHT, f"balance, course {c:g} deg, nominal power {power}", math.radians(c))
        r = runner.power_run(pattern, duration, info, "balance", power=power, course_deg=c)
        out += balance_errors(r.truth, c)
        m = r.truth
        path = (m.path or m.distance) if m is not None else None
        moved.append(path / duration if path is not None and math.isfinite(out[-1]) else math.nan)
    return np.asarray(out), moved


def _ratios(
    geo: Geometry, courses: Sequence[float], speeds: Sequence[float], power: int, k: float
) -> np.ndarray:
    """Per error row (two per course), each motor's ``K u / a`` in that run (0 where it does not drive)."""
    rows = []
    for c, v in zip(courses, speeds, strict=True):
        rims = geo.translation_rim(c)
        peak = max(abs(r) for r in rims)
        row = [k * v / power if abs(r) > 1e-9 * peak else 0.0 for r in rims]  # u / a = v peak / (power peak)
        rows += [row, row]
    return np.asarray(rows, dtype=float)


def balance_model(
    runner: Runner,
    offsets: Sequence[float],
    powers: Sequence[int],
    k: float,
    durations: Sequence[float] | None = None,
    folded: Sequence[float] | None = None,
) -> Balance:
    """Each motor's gain at each nominal power and its speed term that zero the balance runs' errors
    (module docstring); ``k`` is the calibration's K (PWM counts per m/s), the speed terms' scale.

    First the gains: at each power Gauss-Newton on the log-gains, the Jacobian measured at the first
    power that moves the robot and reused at the others, each power starting from the previous one's
    gains, a step kept only when it lowers the rms error (powers at which the robot hardly moves are
    left out). Then the speed terms, from what the gains left over: one linear least squares over
    every power's runs (:func:`~omnibot.calibration.motorfit.speed_step`, each power's rows weighted
    by its rms error), the gains re-centred so that each power's mean stays; kept only when the runs
    through them clearly lower the weighted rms error (:data:`~omnibot.calibration.motorfit.SPEED_KEEP`).
    """
    geo = runner.geometry
    n = geo.motors
    courses = balance_courses(geo, folded)
    result = Balance()
    jac: np.ndarray | None = None
    x = np.zeros(n)
    done: list[tuple[int, float, np.ndarray, list[float]]] = []  # power, duration, errors, speeds
    for j, power in enumerate(powers):
        duration = durations[j] if durations is not None else 1.0
        runner.note(f"balance at {power}")
        e0, moved = _errors(runner, courses, power, constant_gains(offsets, np.zeros(n)), duration)
        if np.count_nonzero(np.isfinite(e0)) < e0.size // 2:
            continue
        e = e0
        if x.any():
            ex, _ = _errors(runner, courses, power, constant_gains(offsets, x), duration)
            if rms(ex) < rms(e0):
                e = ex
            else:
                x = np.zeros(n)
        if jac is None:
            cols = []
            for i in range(n):
                xi = x.copy()
                xi[i] += GAIN_STEP
                ei, _ = _errors(runner, courses, power, constant_gains(offsets, xi), duration)
                cols.append((ei - e) / GAIN_STEP)
            jac = np.column_stack(cols)
        for _ in range(2):
            trial = gain_step(jac, e, x)
            et, _ = _errors(runner, courses, power, constant_gains(offsets, trial), duration)
            if rms(et) < rms(e):
                x, e = trial, et
        result.powers.append(power)
        result.log_gains.append([float(v) for v in x])
        result.before.append(rms(e0))
        result.after.append(rms(e))
        # the busiest wheel's rim speed: the run's speed times its rim factor
        speeds = [v * geo.translation_factor(c) for v, c in zip(moved, courses, strict=True)]
        result.rates += [
            (geo.fold(c), power, u) for c, u in zip(courses, speeds, strict=True) if math.isfinite(u)
        ]
        done.append((power, duration, e, speeds))
    if jac is not None and len(done) >= 2:
        _speed_terms(runner, result, offsets, courses, jac, done, k)
    return result


def _speed_terms(
    runner: Runner,
    result: Balance,
    offsets: Sequence[float],
    courses: Sequence[float],
    jac: np.ndarray,
    done: list[tuple[int, float, np.ndarray, list[float]]],
    k: float,
) -> None:
    """Fit the speed terms on what the gains left over and keep them (with the gains re-centred) when
    the balance runs through them are better (:func:`balance_model`)."""
    geo = runner.geometry
    blocks = [centred_ratios(_ratios(geo, courses, v, p, k)) for p, _, _, v in done]
    centred = np.vstack([b[0] for b in blocks])
    errors = np.concatenate([e for _, _, e, _ in done])
    weights = np.concatenate([np.full(e.size, 1.0 / max(rms(e), 1e-3)) for _, _, e, _ in done])
    c = speed_step(np.vstack([jac] * len(done)), errors, centred, weights)
    if not np.any(np.abs(c) * k >= 0.05):
        return
    log_gains = []
    after = []
    for (power, duration, _, v), (_, mean), x in zip(done, blocks, result.log_gains, strict=True):
        gains = np.maximum(np.exp(x) - c * mean, 0.05)
        motors = constant_gains(offsets, np.log(gains)).model_copy(update={"speed": tuple(c * k)})
        et, _ = _errors(runner, courses, power, motors, duration, v)
        log_gains.append([float(g) for g in np.log(gains)])
        after.append(et)
    new = np.concatenate(after)
    if rms(weights * new) <= SPEED_KEEP * rms(weights * errors):
        result.log_gains = log_gains
        result.after_speed = [rms(e) for e in after]
        result.speed = [round(float(v) * k, 1) for v in c]
        emf = emf_counts(runner.robot)
        result.torque = [round(torque_of(sp, em), 3) for sp, em in zip(result.speed, emf, strict=True)]
