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
* **Speed terms: the stand test** (:func:`stand_test`). The robot lifted (wheels off the floor),
  every motor at three powers; each free wheel's steady speed (its encoder) gives its torque
  constant s (:func:`~omnibot.calibration.motorfit.stand_torque`), and with it the speed term
  ``(s - g) E`` of whatever gain g the floor asks for. The floor's balance runs cannot tell the two
  numbers apart (docs/calibration.md); without a stand (a real robot: not yet asked for; a robot
  without wheel encoders) the speed terms stay 0.
* **Gains** (:func:`balance_model`). Unequal motors turn the body on a straight run and pull it off
  its course. At a few nominal powers the balance runs drive every idle axis and the course halfway
  between two of them, both ways, through the offsets alone, and once more with each motor's power
  up by 8 % (the Jacobian at that power); the errors are each run's course error and its turn per
  metre, and each run's speed is measured (its rim speeds are what the speed terms multiply). One
  gain per motor, its speed term tied to it, is then fitted over every power at once by Gauss-Newton
  (each step driven, kept only when it lowers the errors).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial

import numpy as np

from omnibot.calibration.deadband import MOVED_ANGLE, MOVED_DISTANCE, find_deadband, spread_deadband
from omnibot.calibration.motorfit import (
    ERROR_FLOOR,
    GAIN_STEP,
    STAND_POWERS,
    Balance,
    Stand,
    balance_courses,
    balance_errors,
    constant_gains,
    effective_gains,
    emf_counts,
    floor_information,
    gain_fit_step,
    gain_origin,
    gain_rows,
    identity,
    information,
    model_map,
    offsets_from_deadbands,
    rms,
    stand_torque,
)
from omnibot.calibration.patterns import Geometry, apply_map, top_power
from omnibot.calibration.plan import Plan, speed_range
from omnibot.calibration.runner import Runner
from omnibot.calibration.runs import STRAIGHT, RunInfo
from omnibot.calibration.truth import simulator_of
from omnibot.client import RobotClient
from omnibot.firmware.config import build_config
from omnibot.robot import MotorMapSpec


def motor_deadbands(runner: Runner, step: int = 8, duration: float = 0.5, positions: int = 1) -> list[int]:
    """Each motor's dead band alone: the lowest POWER on that motor only that moves the robot (the
    other wheels' rollers drag by where they stand: the mean over ``positions`` wheel positions,
    :func:`~omnibot.calibration.deadband.spread_deadband`)."""
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

        out.append(spread_deadband(runner, attempt, step, positions))
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


@dataclass
class _Power:
    """One nominal power's balance runs: the errors with the offsets alone, the Jacobian, the speeds."""

    power: int
    duration: float
    e0: np.ndarray
    speeds: list[float]
    """The busiest wheel's rim speed in each course's run (m/s, NaN where unknown)."""
    jac: np.ndarray
    ratios: np.ndarray


def stand_test(runner: Runner, lift: Callable[[bool], None], duration: float = 1.6) -> Stand | None:
    """The robot on a stand (``lift(True)``; lowered again after): every motor at each of
    :data:`~omnibot.calibration.motorfit.STAND_POWERS` for ``duration`` s, each free wheel's steady
    speed from its encoder over the run's second half; the torque constants
    (:func:`~omnibot.calibration.motorfit.stand_torque`). None without an encoder on every wheel or
    when a wheel did not turn."""
    robot, tap = runner.robot, runner.tap
    if not robot.has_wheel_encoders:
        return None
    cpr = {e.wheel: e.counts_per_rev for e in robot.encoders.motors}
    per_count = [2.0 * math.pi / cpr[w.name] for w in robot.wheels]
    powers: list[float] = []
    speeds: list[list[float]] = []
    lift(True)
    try:
        for frac in STAND_POWERS:
            power = round(frac * runner.geometry.pwm_max)
            runner.note(f"stand at {power}")
            tap.record()
            pattern = [power] * runner.geometry.motors
            runner.power_run(pattern, duration, RunInfo(STRAIGHT, f"stand test, power {power}"), "stand")
            log = [t for t in tap.take_log() if t.encoders is not None]
            if not log:
                return None
            start = log[0].controller_time
            steady = [t for t in log if 0.5 * duration <= t.controller_time - start <= 0.95 * duration]
            a, b = (steady[0], steady[-1]) if len(steady) >= 2 else (None, None)
            if a is None or b is None or a.encoders is None or b.encoders is None:
                return None
            dt = b.controller_time - a.controller_time
            powers.append(float(power))
            speeds.append(
                [(y - x) * c / dt for x, y, c in zip(a.encoders, b.encoders, per_count, strict=True)]
            )
    finally:
        lift(False)
    stand = stand_torque(robot, powers, speeds)
    return stand if all(math.isfinite(t) and t > 0.0 for t in stand.torque) else None


def balance_model(
    runner: Runner,
    offsets: Sequence[float],
    powers: Sequence[int],
    k: float,
    durations: Sequence[float] | None = None,
    folded: Sequence[float] | None = None,
    stand: Stand | None = None,
) -> Balance:
    """Each motor's gain (and, with the ``stand`` test's torque constants s, its speed term
    ``(s - g) E``) that zero the balance runs' errors at every power at once (module docstring);
    ``k`` is the calibration's K (PWM counts per m/s).

    At each power: the runs through the offsets alone, and the finite-difference Jacobian of the
    errors against each motor's power (powers at which the robot hardly moves are left out). Then
    Gauss-Newton on the gains over every power's runs together
    (:func:`~omnibot.calibration.motorfit.gain_fit_step`; each power's rows weighted by 1 / its rms
    error at the current gains, so that a power whose runs no map can balance, such as one where the
    drivers limit the current, does not pull the others), each step driven and kept only when it
    lowers the errors (:func:`_score`).
    """
    geo = runner.geometry
    n = geo.motors
    courses = balance_courses(geo, folded)
    result = Balance(stand=stand)
    blocks: list[_Power] = []
    for j, power in enumerate(powers):
        block = _power_runs(
            runner, courses, offsets, power, durations[j] if durations is not None else 1.0, k
        )
        if block is None:
            continue
        blocks.append(block)
        result.rates += [
            (geo.fold(c), power, u) for c, u in zip(courses, block.speeds, strict=True) if math.isfinite(u)
        ]
    if not blocks:
        return result
    torque = np.asarray(stand.torque if stand is not None else (1.0,) * n, dtype=float)
    emf = np.asarray(emf_counts(runner.robot)) if stand is not None else np.zeros(n)
    rows = np.vstack([gain_rows(b.jac, b.ratios, emf, k) for b in blocks])
    jac = np.vstack([b.jac for b in blocks])
    ratios = np.vstack([b.ratios for b in blocks])
    gains, speed, errors = _fit_gains(runner, courses, offsets, blocks, rows, torque, emf, k)
    weights = _weights(errors)
    scatter = rms(weights * np.concatenate(errors))
    scatter = scatter if math.isfinite(scatter) else 1.0
    result.information = information(rows, weights, scatter, torque)
    result.floor_only = floor_information(jac, ratios, weights, scatter)
    result.powers = [b.power for b in blocks]
    result.log_gains = [[float(math.log(g)) for g in gains] for _ in blocks]
    result.before = [rms(b.e0) for b in blocks]
    result.after = [rms(e) for e in errors]
    if stand is not None:
        result.speed = [round(float(c), 1) for c in speed]
        result.torque = [round(float(t), 3) for t in torque]
    return result


def _power_runs(
    runner: Runner, courses: Sequence[float], offsets: Sequence[float], power: int, duration: float, k: float
) -> _Power | None:
    """The balance runs at one ``power``: the errors through the offsets alone and the
    finite-difference Jacobian against each motor's gain; None where the robot hardly moves."""
    geo = runner.geometry
    n = geo.motors
    runner.note(f"balance at {power}")
    e0, moved = _errors(runner, courses, power, constant_gains(offsets, np.zeros(n)), duration)
    if np.count_nonzero(np.isfinite(e0)) < e0.size // 2:
        return None
    cols = []
    for i in range(n):
        xi = np.zeros(n)
        xi[i] = GAIN_STEP
        ei, _ = _errors(runner, courses, power, constant_gains(offsets, xi), duration)
        cols.append((ei - e0) / GAIN_STEP)
    # the busiest wheel's rim speed: the run's speed times its rim factor
    speeds = [v * geo.translation_factor(c) for v, c in zip(moved, courses, strict=True)]
    ratios = _ratios(geo, courses, speeds, power, k)
    return _Power(power, duration, e0, speeds, np.column_stack(cols), ratios)


def _fit_gains(
    runner: Runner,
    courses: Sequence[float],
    offsets: Sequence[float],
    blocks: list[_Power],
    rows: np.ndarray,
    torque: np.ndarray,
    emf: np.ndarray,
    k: float,
) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """Gauss-Newton on the gains over every power's runs (:func:`balance_model`), each step driven
    and kept only when it lowers the errors: the gains, the speed terms and the runs' errors."""
    n = runner.geometry.motors
    jac = np.vstack([b.jac for b in blocks])
    ratios = np.vstack([b.ratios for b in blocks])
    gains = np.ones(n)
    speed = np.zeros(n)  # the runs so far: the offsets alone
    errors = [b.e0 for b in blocks]
    step = 1.0
    for _ in range(MODEL_ROUNDS):
        acted = effective_gains(gains, speed, ratios, k)
        origin = gain_origin(np.concatenate(errors), jac, acted, ratios, torque, emf, k)
        trial = gains + step * (gain_fit_step(rows, origin, _weights(errors), torque) - gains)
        trial_speed = (torque - trial) * emf
        motors = model_map(offsets, trial, trial_speed)
        got = [_errors(runner, courses, b.power, motors, b.duration, b.speeds)[0] for b in blocks]
        if _score(got, blocks) < _score(errors, blocks):
            gains, speed, errors, step = trial, trial_speed, got, 1.0
        else:
            step *= 0.5  # the linear model overshot: half the step next time
    return gains, speed, errors


WEIGHT_POWER = 2.0
"""Each power's rows are weighted by 1 / its rms error to this power (least squares: to twice it): the
powers whose runs the map balances lead; one near the dead band (erratic) or where the drivers limit the
current (no map balances it) hardly counts."""
MODEL_ROUNDS = 3
"""Gauss-Newton steps of the gain fit, each driven (8 runs per power on omni4); a step that does not
lower the errors is not kept and the next one is half as long."""


def _weights(errors: Sequence[np.ndarray]) -> np.ndarray:
    """Each power's rows weighted by 1 / its rms error (at least :data:`ERROR_FLOOR`)."""
    return np.concatenate([np.full(e.size, 1.0 / max(rms(e), ERROR_FLOOR) ** WEIGHT_POWER) for e in errors])


def _score(errors: Sequence[np.ndarray], blocks: Sequence[_Power]) -> float:
    """The rms over the powers of each power's rms error relative to its runs through the offsets alone."""
    rel = [rms(e) / max(rms(b.e0), ERROR_FLOOR) for e, b in zip(errors, blocks, strict=True)]
    return float(np.sqrt(np.mean(np.square(rel))))


Lift = Callable[[RobotClient, bool], None]
"""Puts the robot on a stand, every wheel off the floor (True), and back where it stood (False)."""


def fit_motor_map(
    runner: Runner, plan: Plan, notes: list[str], stand: Lift | None = None
) -> tuple[MotorMapSpec, Balance]:
    """Offsets from the motors' own dead bands, the torque constants from the stand test (the
    simulator's wheels lifted, else ``stand``; neither: no speed terms), then the gains from the
    balance runs (motors.py) at nominal powers spread over what the robot's speed range needs (by the
    described K)."""
    geo, robot = runner.geometry, runner.robot
    runner.motors = None
    runner.rate = None
    rotation = find_deadband(runner, None, plan.deadband_step, positions=plan.deadband_positions).power
    single = motor_deadbands(runner, plan.deadband_step, positions=plan.deadband_positions)
    offsets = offsets_from_deadbands(single, rotation, geo.pwm_max)
    if not any(offsets):
        notes.append(f"motor dead bands {single} (rotation {rotation}): no offsets")
    top = top_power(MotorMapSpec(offset=offsets, gain=identity(geo.motors).gain), geo.pwm_max)
    k = float(build_config(robot)["k"])
    slow, fast = speed_range(robot, plan.move_length)
    factors = [geo.translation_factor(c) for c in plan.calibrated_courses(geo)]
    lo, hi = k * slow * min(factors), min(2.0 * k * fast * max(factors), 0.9 * top)
    n = max(1, plan.balance_levels)
    powers = sorted({max(1, round(lo * (hi / lo) ** (i / max(n - 1, 1)))) for i in range(n)})
    # long enough for about half the reference move at the speed each power is meant for
    durations = [min(max(0.5 * plan.move_length * k * max(factors) / p, 1.0), 3.0) for p in powers]
    lift = simulator_lift(runner.client) or (partial(stand, runner.client) if stand is not None else None)
    torque = stand_test(runner, lift) if lift is not None else None
    if torque is None:
        notes.append(
            "motor map: no stand test (nobody to lift the robot, or a wheel without an encoder), so no speed terms"
        )
    balance = balance_model(runner, offsets, powers, k, durations, stand=torque)
    runner.rate = balance.rate if balance.rates else None
    speed = tuple(balance.speed) if balance.speed else None
    return MotorMapSpec(offset=offsets, gain=balance.tables(geo.motors), speed=speed), balance


def simulator_lift(client: RobotClient) -> Callable[[bool], None] | None:
    """The stand of a simulated robot: its wheels lifted off the floor; None on another link."""
    sim = simulator_of(client)
    if sim is None:
        return None

    def lift(up: bool) -> None:
        for wheel in sim.robot.wheels:
            sim.lift_wheel(wheel.name, up)

    return lift
