"""The whole calibration of one robot: per surface, then averaged over the surfaces.

Per surface (:func:`calibrate_surface`), on one client::

    telemetry on -> gyro bias at standstill -> accuracy before
    -> motor map -> dead bands -> straight sweeps (each calibrated course) -> roller drag
    -> rotation sweep -> fit K, K_l, K_r
    -> upload -> curved MOVEs, fit K_t (rounds) -> upload -> roller drag's coast from MOVEs -> upload
    -> rotation test (gyro scale, wheel base) -> squares CCW and CW (UMBmark) -> accuracy after

Over surfaces (:func:`calibrate`): each surface as above, then the averaged calibration (seed 000
averaged wood and carpet), uploaded and checked on every surface again.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager
from dataclasses import dataclass, field
from functools import partial
from typing import Any

from omnibot.calibration.accuracy import AccuracyPlan, AccuracyRow, reach_speed, run_accuracy
from omnibot.calibration.experiments import (
    Plan,
    Runner,
    RunResult,
    find_deadband,
    rotation_sweep,
    speed_range,
    straight_sweep,
    turning_runs,
)
from omnibot.calibration.fits import SurfaceFit, average_kt, build_spec, fit_kt, fit_surface, robot_table
from omnibot.calibration.gyro import GyroCalibration, calibrate_gyro, standstill_bias
from omnibot.calibration.motors import (
    Balance,
    balance_courses,
    balance_gains,
    identity,
    motor_deadbands,
    offsets_from_deadbands,
)
from omnibot.calibration.patterns import Geometry, top_power
from omnibot.calibration.rollers import (
    SHARES,
    axis_courses,
    correct_runs,
    fit_rollers,
    offset_shift,
    roller_runs,
    tune_coast,
)
from omnibot.calibration.slip import slip_step
from omnibot.calibration.tap import TelemetryTap
from omnibot.calibration.truth import ROTATE, SQUARE, STRAIGHT, Ask, RunInfo, TruthContext, make_truth
from omnibot.calibration.umbmark import OdometryCalibration, SquareRun, calibrate_odometry, drive_square
from omnibot.client.client import RobotClient
from omnibot.errors import ConfigError
from omnibot.firmware.config import build_config
from omnibot.navigation.slipcal import SlipCalibration
from omnibot.progress import Progress
from omnibot.protocol import codes
from omnibot.robot.description import CalibrationSpec, MotorMapSpec, RobotDescription

ProgressFactory = Callable[[str, int], AbstractContextManager[Progress | None]]
"""(description, expected runs) -> a context giving a progress bar (or None)."""


@contextmanager
def no_progress(desc: str, total: int) -> Iterator[Progress | None]:
    yield None


@dataclass
class SurfaceSession:
    """Everything measured and fitted on one surface."""

    surface: str
    truth: str
    fit: SurfaceFit
    spec: CalibrationSpec
    runs: list[RunResult]
    gyro: GyroCalibration | None = None
    odometry: OdometryCalibration | None = None
    before: list[AccuracyRow] | None = None
    after: list[AccuracyRow] | None = None
    notes: list[str] = field(default_factory=list)
    slip: SlipCalibration | None = None
    """The floor's wheel creep (driven-wheel odometry), when the robot has wheel encoders."""
    reach: float | None = None
    """m/s: the fastest MOVE of the reference length the floor's tables power on every course
    (:func:`~omnibot.calibration.accuracy.reach_speed`)."""


@dataclass
class CalibrationResult:
    robot: RobotDescription
    sessions: list[SurfaceSession]
    average: CalibrationSpec | None = None
    average_checks: dict[str, list[AccuracyRow]] = field(default_factory=dict)

    @property
    def chosen(self) -> CalibrationSpec:
        """The averaged calibration over several surfaces, else the one surface's."""
        return self.average if self.average is not None else self.sessions[0].spec

    @property
    def gyro(self) -> GyroCalibration | None:
        cals = [s.gyro for s in self.sessions if s.gyro is not None]
        if not cals:
            return None
        scales = [c.scale for c in cals if c.scale is not None]
        last = cals[-1]
        return GyroCalibration(
            bias=last.bias,
            bias_std=last.bias_std,
            samples=last.samples,
            scale=statistics.fmean(scales) if scales else None,
            rotations=sum(c.rotations for c in cals),
        )

    @property
    def odometry(self) -> OdometryCalibration | None:
        cals = [s.odometry for s in self.sessions if s.odometry is not None]
        if len(cals) <= 1:
            return cals[0] if cals else None
        r = statistics.fmean(c.wheel_radius_scale for c in cals)
        w = statistics.fmean(c.rotation_scale for c in cals)
        return OdometryCalibration(
            wheel_radius_scale=round(r, 4),
            wheel_base_scale=round(r / w, 4),
            rotation_scale=round(w, 4),
            straight_runs=sum(c.straight_runs for c in cals),
            rotation_runs=sum(c.rotation_runs for c in cals),
        )


def accuracy_runs(accuracy: AccuracyPlan, robot: RobotDescription) -> int:
    """The runs of one accuracy check (:func:`~omnibot.calibration.accuracy.run_accuracy`)."""
    moves = len(accuracy.courses_deg) * len(accuracy.move_speeds(robot)) * (2 if accuracy.back else 1)
    return moves + 2 * len(accuracy.rotations)


DEADBAND_RUNS = 10
"""Runs a dead-band search takes, about (a sweep upward in ``deadband_step`` counts, then bisection)."""


def expected_runs(
    plan: Plan,
    geometry: Geometry,
    accuracy: AccuracyPlan | None,
    robot: RobotDescription,
    upload: bool = True,
) -> dict[str, int]:
    """The runs each phase of one surface is expected to take, in the order they come (for the
    progress bar). Exact where a phase's count is fixed; the dead-band searches and the sweeps
    adapt to the robot, so theirs are estimates the bar corrects as each phase ends (:class:`Tally`)."""
    courses = len(plan.calibrated_courses(geometry))
    checks = accuracy_runs(accuracy, robot) if accuracy is not None else 0
    powers = max(1, plan.balance_levels)
    balance = len(balance_courses(geometry)) * (3 * powers + powers - 1 + geometry.motors)
    rollers = plan.roller_rounds > 0 and all(geometry.roller_pitch)
    axes = len(axis_courses(geometry))
    phases = {
        "before": checks,
        "motor map": (1 + geometry.motors) * DEADBAND_RUNS + balance if plan.motor_map else 0,
        "dead bands": (courses + 1) * (3 if plan.motor_map else DEADBAND_RUNS),
        "sweeps": courses * plan.levels * plan.directions * 2,
        "roller drag": len(SHARES) * (1 + plan.roller_rounds * axes) if rollers else 0,
        "rotation sweep": plan.levels * 2 * 2,
        "turns": plan.turn_rounds * len(plan.turn_curvatures) * len(plan.turn_courses_deg) * 2
        if upload
        else 0,
        "roller gains": 3 * plan.roller_rounds * axes if rollers and upload else 0,
        "rotation test": 2,
        "squares": 2,
        "after": checks if upload else 0,
    }
    return {name: n for name, n in phases.items() if n}


class Tally:
    """Keeps a progress bar's total true: the runs done plus the runs the phases still to come are
    expected to take. Each phase's end (:meth:`done`) replaces its estimate by what it really took, so
    when the last one ends the total is the number of runs driven."""

    def __init__(self, bar: Progress | None, phases: dict[str, int]) -> None:
        self.bar = bar
        self.left = dict(phases)
        self.runs = 0
        """Runs counted so far (the bar's n)."""

    @property
    def total(self) -> int:
        return self.runs + sum(self.left.values())

    def update(self, n: float | None = 1) -> bool | None:
        self.runs += int(n or 0)
        return self.bar.update(n) if self.bar is not None else None

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        if self.bar is not None:
            self.bar.set_postfix_str(s, refresh)

    def done(self, *phases: str) -> None:
        """These phases have ended (or will not run): their runs are all counted."""
        for phase in phases:
            self.left.pop(phase, None)
        self.recount()

    def finish(self) -> None:
        """Every phase has ended: the total is the runs driven."""
        self.left.clear()
        self.recount()

    def recount(self) -> None:
        if self.bar is not None and hasattr(self.bar, "total"):
            self.bar.total = self.total
            refresh = getattr(self.bar, "refresh", None)
            if refresh is not None:
                refresh()


def _open_loop(client: RobotClient) -> None:
    """Clear the simulation and closed-loop MODE bits (calibration is of the open-loop powers)."""
    mode = client.status().mode
    unwanted = codes.MODE_SIMULATION | codes.MODE_CLOSED_LOOP
    if mode & unwanted:
        client.mode(mode & ~unwanted)


def calibrate_surface(
    client: RobotClient,
    robot: RobotDescription,
    surface: str,
    *,
    truth: str = "sim",
    plan: Plan | None = None,
    accuracy: AccuracyPlan | None = None,
    ask: Ask = input,
    progress: ProgressFactory = no_progress,
    upload: bool = True,
) -> SurfaceSession:
    """Measure, fit and (``upload``) apply the calibration of ``robot`` on one surface."""
    plan = plan or Plan()
    geometry = Geometry.of(robot)
    courses = plan.calibrated_courses(geometry)
    client.stop()
    _open_loop(client)
    tap = TelemetryTap(client, robot)
    tap.start()
    source = make_truth(truth, TruthContext(client, robot, tap, ask))
    notes: list[str] = []
    phases = expected_runs(plan, geometry, accuracy, robot, upload)
    with progress(f"calibrate {robot.name} on {surface}", sum(phases.values())) as bar:
        tally = Tally(bar, phases)
        runner = Runner(client, robot, source, tap, settle=plan.settle, progress=tally)
        try:
            bias = standstill_bias(tap, plan.gyro_still) if tap.gyro else None
            before = run_accuracy(runner, accuracy) if accuracy is not None else None
            tally.done("before")

            motors, balance = None, None
            if plan.motor_map:
                motors, balance = fit_motor_map(runner, plan, notes)
                runner.motors = motors
            tally.done("motor map")
            deadbands = {f"course:{c:g}": find_deadband(runner, c, plan.deadband_step).power for c in courses}
            deadbands["rotation"] = find_deadband(runner, None, plan.deadband_step).power
            tally.done("dead bands")
            straight: list[RunResult] = []
            for c in courses:
                straight += straight_sweep(runner, plan, c, deadbands[f"course:{c:g}"])
            tally.done("sweeps")
            rollers = None
            if (
                plan.roller_rounds > 0
                and all(geometry.roller_pitch)
                and source.can(RunInfo(STRAIGHT, "", 0.0))
            ):
                axis = deadbands.get("course:0") or find_deadband(runner, 0.0, plan.deadband_step).power
                rollers = fit_rollers(geometry, roller_runs(runner, plan, axis, plan.roller_rounds))
                if rollers is None:
                    notes.append("roller drag: the runs could not tell it (no drag term uploaded)")
                else:
                    straight = correct_runs(geometry, rollers, straight)
            tally.done("roller drag")
            rotation = rotation_sweep(runner, plan, deadbands["rotation"])
            tally.done("rotation sweep")
            fit = fit_surface(
                surface,
                straight,
                rotation,
                deadbands,
                geometry,
                move_length=plan.move_length,
                rotate_angle=plan.rotate_angle,
            )
            fit.motors, fit.balance, fit.rollers = motors, balance, rollers
            described = robot.calibration.k if robot.calibration is not None else None
            if described is not None and not 1 / 3 < fit.k / described < 3:
                notes.append(
                    f"the fitted K ({fit.k:g}) is far from the description's ({described:g}): the runs may "
                    "be too short for this robot (a heavy one coasts for long; try a longer --move-length) "
                    "- check fig5_rates.png before using the tables"
                )
            kt = robot_table(robot, "k_t")
            spec = build_spec([fit], robot, geometry, kt)
            if upload:
                client.upload_calibration(spec)
                for _ in range(plan.turn_rounds):
                    turns = turning_runs(runner, plan, spec.k)
                    new_kt = fit_kt(turns, spec.k_t)
                    if new_kt is None:
                        notes.append("no curved MOVE turned measurably: K_t kept")
                        break
                    spec = build_spec([fit], robot, geometry, new_kt)
                    client.upload_calibration(spec)
            else:
                notes.append("not uploaded: K_t (measured with curved MOVEs) kept from the description")
            fit.kt = spec.k_t
            tally.done("turns")
            if upload and rollers is not None and spec.rollers is not None and spec.rollers.coast is not None:
                spec = tune_rollers(runner, fit, spec, plan, notes)
            tally.done("roller gains")
            reach = reach_speed(robot, spec, plan.move_length)
            top = speed_range(robot, plan.move_length)[1]
            if reach is None or reach < top:
                notes.append(
                    f"MOVEs of {plan.move_length:g} m reach "
                    + ("no speed" if reach is None else f"{reach:g} m/s")
                    + f" on every course with these tables (the robot's top: {top:g} m/s); faster ones "
                    "saturate a motor (the controller warns 11, speed reduced) and fall short"
                )

            if bias is not None:  # the bias wanders: measure it again right before the rotation test
                bias = standstill_bias(tap, plan.gyro_still) or bias
            rot_test = rotation_test(runner, plan)
            tally.done("rotation test")
            gyro = calibrate_gyro(bias, rot_test) if bias is not None else None
            squares: list[SquareRun] = []
            if tap.odometry is not None and source.can(RunInfo(SQUARE, "")):
                speed = plan.square_speed or round(0.5 * sum(speed_range(robot, plan.move_length)), 2)
                rate = rotation_test_rate(robot)
                squares = [drive_square(runner, plan.square_side, speed, rate, ccw) for ccw in (True, False)]
            tally.done("squares")
            odometry = None
            if tap.odometry is not None and source.exact:
                odometry = calibrate_odometry(robot, straight, rot_test, squares)
            elif tap.odometry is not None:
                notes.append(
                    f"odometry corrections need an independent truth (sim, csv, tape), not {source.name}"
                )
            after = run_accuracy(runner, accuracy) if accuracy is not None and upload else None
            tally.finish()
        finally:
            runner.close()
            tap.stop()
    slip = None
    if plan.slip and tap.odometry is not None and source.exact:
        with progress(f"wheel slip on {surface}", 12) as slip_bar:
            try:
                slip = slip_step(client, robot, source, slip_bar)
            except ConfigError as exc:
                notes.append(f"wheel slip not calibrated: {exc}")
            finally:  # back to what the rest of the calibration expects (the runs end stopped)
                if client.binary:
                    client.use_text()
                _open_loop(client)
    elif plan.slip and tap.odometry is not None:
        notes.append(f"wheel slip needs an independent truth (sim, csv, tape), not {source.name}")
    return SurfaceSession(
        surface=surface,
        truth=source.describe(),
        fit=fit,
        spec=spec,
        runs=runner.log,
        gyro=gyro,
        odometry=odometry,
        before=before,
        after=after,
        notes=notes,
        slip=slip,
        reach=reach,
    )


def tune_rollers(
    runner: Runner, fit: SurfaceFit, spec: CalibrationSpec, plan: Plan, notes: list[str]
) -> CalibrationSpec:
    """The roller drag's coast from MOVEs and the motor axes' offsets evened out by the same MOVEs
    (rollers.py); the new section, uploaded. ``fit`` gets the coast and the shifted motor map."""
    robot, geometry = runner.robot, runner.geometry
    assert fit.rollers is not None
    bottom, top = speed_range(robot, plan.move_length)
    reach = reach_speed(robot, spec, plan.move_length)
    # up to 90 % of the reach: at the reach itself a motor runs out of power at the worst wheel
    # position, which no gain can make up for
    fastest = max(bottom, 0.9 * min(top, reach or top))
    speeds = sorted({round(bottom + (fastest - bottom) * k / 3, 2) for k in range(4)})
    fit.coast = tune_coast(runner, spec, fit.rollers, speeds, plan.move_length, plan.roller_rounds)
    if fit.coast is None:
        notes.append("roller drag: the MOVEs could not tell its coast; the drag runs' own is kept")
        return spec
    if fit.motors is not None:
        shift = offset_shift(geometry, fit.coast.ahead)
        offsets = tuple(max(0.0, round(o + d, 1)) for o, d in zip(fit.motors.offset, shift, strict=True))
        fit.motors = MotorMapSpec(offset=offsets, gain=fit.motors.gain)
        runner.motors = fit.motors
    spec = build_spec([fit], robot, geometry, spec.k_t)
    runner.client.upload_calibration(spec)
    return spec


def fit_motor_map(runner: Runner, plan: Plan, notes: list[str]) -> tuple[MotorMapSpec, Balance]:
    """Offsets from the motors' own dead bands, then gains from the balance runs (motors.py) at
    nominal powers spread over what the robot's speed range needs (by the described K)."""
    geo, robot = runner.geometry, runner.robot
    runner.motors = None
    rotation = find_deadband(runner, None, plan.deadband_step).power
    single = motor_deadbands(runner, plan.deadband_step)
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
    balance = balance_gains(runner, offsets, powers, durations)
    return MotorMapSpec(offset=offsets, gain=balance.tables(geo.motors)), balance


def rotation_test_rate(robot: RobotDescription) -> float:
    """rad/s: 90 degrees/s, or less where the gyro's range or the robot's limit is lower."""
    rate = math.radians(90.0)
    if robot.gyro is not None:
        rate = min(rate, 0.5 * robot.gyro.range)
    return min(rate, 0.5 * robot.limits.angular_speed_max)


def rotation_test(runner: Runner, plan: Plan) -> list[RunResult]:
    """ROTATE ``plan.rotation_turns`` full turns each way (gyro scale, rotation scale of odometry)."""
    rate = round(math.degrees(rotation_test_rate(runner.robot)))
    angle = 360.0 * plan.rotation_turns
    out = []
    for sign in (1, -1):
        a = sign * angle
        info = RunInfo(ROTATE, f"rotation test: {a:+.0f} deg at {rate} deg/s")
        runner.note(f"rotation test {a:+.0f}")
        out.append(
            runner.run(
                info,
                partial(runner.client.rotate, math.radians(a), math.radians(rate)),
                angle / rate,
                "rotation-test",
                sign=sign,
                commanded=math.radians(angle),
            )
        )
    return out


ClientOpener = Callable[[str], AbstractContextManager[RobotClient]]
"""surface -> a context giving a client whose robot stands on that surface."""


def check_average(
    client: RobotClient,
    robot: RobotDescription,
    spec: CalibrationSpec,
    *,
    truth: str,
    accuracy: AccuracyPlan,
    ask: Ask = input,
    progress: Progress | None = None,
) -> list[AccuracyRow]:
    """Upload ``spec`` and run the accuracy check on the robot as it stands."""
    client.stop()
    _open_loop(client)
    client.upload_calibration(spec)
    tap = TelemetryTap(client, robot)
    tap.start()
    runner = Runner(
        client, robot, make_truth(truth, TruthContext(client, robot, tap, ask)), tap, progress=progress
    )
    try:
        return run_accuracy(runner, accuracy)
    finally:
        runner.close()
        tap.stop()


def calibrate(
    robot: RobotDescription,
    surfaces: list[str],
    open_client: ClientOpener,
    *,
    truth: str | Callable[[RobotClient], str] = "sim",
    plan: Plan | None = None,
    accuracy: AccuracyPlan | None = None,
    ask: Ask = input,
    progress: ProgressFactory = no_progress,
    upload: bool = True,
) -> CalibrationResult:
    """Calibrate on every surface, then average and check the average on every surface."""
    plan = plan or Plan()
    sessions = []

    def truth_for(client: RobotClient) -> str:
        return truth if isinstance(truth, str) else truth(client)

    for surface in surfaces:
        with open_client(surface) as client:
            sessions.append(
                calibrate_surface(
                    client,
                    robot,
                    surface,
                    truth=truth_for(client),
                    plan=plan,
                    accuracy=accuracy,
                    ask=ask,
                    progress=progress,
                    upload=upload,
                )
            )
    result = CalibrationResult(robot, sessions)
    if len(sessions) > 1:
        geometry = Geometry.of(robot)
        fits = [s.fit for s in sessions]
        result.average = build_spec(fits, robot, geometry, average_kt(fits))
        if accuracy is not None and upload:
            for surface in surfaces:
                with (
                    open_client(surface) as client,
                    progress(f"check the average on {surface}", accuracy_runs(accuracy, robot)) as bar,
                ):
                    result.average_checks[surface] = check_average(
                        client,
                        robot,
                        result.average,
                        truth=truth_for(client),
                        accuracy=accuracy,
                        ask=ask,
                        progress=bar,
                    )
    return result


def describe_spec(spec: CalibrationSpec) -> dict[str, Any]:
    """A calibration section as plain data (the YAML layout of a description's ``calibration:``)."""
    out: dict[str, Any] = {"k": spec.k}
    if spec.k_l is not None:
        out["k_l"] = {
            "courses_deg": list(spec.k_l.courses_deg),
            "curves": [{"x": [int(x) for x in c.x], "y": list(c.y)} for c in spec.k_l.curves],
        }
    for name in ("k_t", "k_r"):
        t = getattr(spec, name)
        if t is not None:
            out[name] = {"x": [int(x) for x in t.x], "y": list(t.y)}
    if spec.motors is not None:
        out["motors"] = {
            "offset": list(spec.motors.offset),
            "gain": [{"x": [int(x) for x in g.x], "y": list(g.y)} for g in spec.motors.gain],
        }
    if spec.rollers is not None:
        out["rollers"] = {"cos": list(spec.rollers.cos), "sin": list(spec.rollers.sin)}
        if spec.rollers.coast is not None:
            out["rollers"]["coast"] = {"x": list(spec.rollers.coast.x), "y": list(spec.rollers.coast.y)}
    return out
