"""The motor map, measured: each motor's dead band alone and the balance runs (the fit is
:mod:`omnibot.calibration.motorfit`).

The firmware gives motor i ``sign(a) (offset_i + gain_i(|a|) |a|)`` for the nominal power ``a``
of the calibration factors (docs/firmware.md); :func:`~omnibot.calibration.patterns.map_power` is the same on the host, so the
sweeps' raw POWER patterns drive the robot exactly as the firmware will.

* **Offsets.** A motor's Coulomb friction needs a fixed power before its wheel turns at all; below
  it a slowly turning wheel (the side pair of an omni4 on course 15) stands still and the robot
  leaves its course. Each motor's dead band is found alone (:func:`motor_deadbands`: that motor's
  POWER only; its wheel also pushes the robot, so the number is a little high) and scaled so that
  their mean is the dead band of rotation in place, where no idle roller drags:
  ``offset_i = deadband_i * rotation / mean(deadband)``.
* **Gains.** Unequal motors turn the body on a straight run and pull it off its course. At a few
  nominal powers the balance runs drive every idle axis and the course halfway between two of
  them, both ways; the errors are each run's course error and its turn per metre. The log-gains
  (their sum held at zero: a common factor is the K_l tables' business) are found by Gauss-Newton
  with a finite-difference Jacobian at the first power that moves the robot, reused (chord method)
  at the others, a step kept only when it lowers the rms error (:func:`balance_gains`). Measuring
  the Jacobian again at every power, and Broyden updates of it, were tried: on carpet the steps then
  went astray (the acceptance check's carpet mean rose from 2.8 % to 6.7 and 4.8 %).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from omnibot.calibration.experiments import MOVED_ANGLE, MOVED_DISTANCE, Runner, lowest_moving
from omnibot.calibration.motorfit import (
    GAIN_STEP,
    Balance,
    balance_courses,
    balance_errors,
    constant_gains,
    gain_step,
    rms,
)
from omnibot.calibration.patterns import apply_map
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
    runner: Runner, courses: Sequence[float], power: int, motors: MotorMapSpec, duration: float
) -> np.ndarray:
    """Course error (rad) and turn (rad per metre of path) of a run on each course; NaN where the
    robot hardly moved or the truth cannot tell."""
    geo = runner.geometry
    out: list[float] = []
    for c in courses:
        rims = geo.translation_rim(c)
        peak = max(abs(v) for v in rims)
        pattern = apply_map(motors, [power * v / peak for v in rims], geo.pwm_max)
        info = RunInfo(STRAIGHT, f"balance, course {c:g} deg, nominal power {power}", math.radians(c))
        r = runner.power_run(pattern, duration, info, "balance", power=power, course_deg=c)
        out += balance_errors(r.truth, c)
    return np.asarray(out)


def balance_gains(
    runner: Runner,
    offsets: Sequence[float],
    powers: Sequence[int],
    durations: Sequence[float] | None = None,
    folded: Sequence[float] | None = None,
) -> Balance:
    """Log-gains at each nominal power that zero the balance runs' errors (module docstring).

    Powers at which the robot hardly moves are left out; the Jacobian is measured at the first power
    that moves it and reused at the others, each starting from the previous power's gains.
    """
    geo = runner.geometry
    n = geo.motors
    courses = balance_courses(geo, folded)
    result = Balance()
    jac: np.ndarray | None = None
    x = np.zeros(n)
    for k, power in enumerate(powers):
        duration = durations[k] if durations is not None else 1.0
        runner.note(f"balance at {power}")
        e0 = _errors(runner, courses, power, constant_gains(offsets, np.zeros(n)), duration)
        if np.count_nonzero(np.isfinite(e0)) < e0.size // 2:
            continue
        e = e0
        if x.any():
            ex = _errors(runner, courses, power, constant_gains(offsets, x), duration)
            if rms(ex) < rms(e0):
                e = ex
            else:
                x = np.zeros(n)
        if jac is None:
            cols = []
            for i in range(n):
                xi = x.copy()
                xi[i] += GAIN_STEP
                ei = _errors(runner, courses, power, constant_gains(offsets, xi), duration)
                cols.append((ei - e) / GAIN_STEP)
            jac = np.column_stack(cols)
        for _ in range(2):
            trial = gain_step(jac, e, x)
            et = _errors(runner, courses, power, constant_gains(offsets, trial), duration)
            if rms(et) < rms(e):
                x, e = trial, et
        result.powers.append(power)
        result.log_gains.append([float(v) for v in x])
        result.before.append(rms(e0))
        result.after.append(rms(e))
    return result
