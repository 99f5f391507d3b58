"""The named steps of one surface's calibration (:data:`STEPS`, in order), each reading and filling
in the :class:`~omnibot.calibration.surface_run.SurfaceRun`, and the experiments they drive beyond
:mod:`omnibot.calibration.experiments`: the motor map, the roller gains, the rotation test."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

from omnibot.calibration.accuracy import (
    checked_reach,
    checked_reach_table,
    describe_reach,
    reach_speed,
)
from omnibot.calibration.check import run_accuracy
from omnibot.calibration.deadband import find_deadband
from omnibot.calibration.experiments import (
    drive_square,
    rotation_sweep,
    slow_moves,
    straight_sweep,
    turning_runs,
)
from omnibot.calibration.fits import (
    SurfaceFit,
    anchor_slow_end,
    build_spec,
    fit_kt,
    fit_surface,
    robot_table,
)
from omnibot.calibration.gyro import calibrate_gyro
from omnibot.calibration.motors import fit_motor_map
from omnibot.calibration.plan import Plan, speed_range
from omnibot.calibration.reachmoves import measure_reach
from omnibot.calibration.rollerfit import axis_courses, correct_runs, fit_rollers, offset_shift
from omnibot.calibration.rollers import roller_runs, tune_coast
from omnibot.calibration.runner import Runner
from omnibot.calibration.runs import ROTATE, SQUARE, STRAIGHT, RunInfo, RunResult
from omnibot.calibration.surface_run import SurfaceRun
from omnibot.calibration.tap import standstill_bias
from omnibot.calibration.umbmark import calibrate_odometry
from omnibot.robot import CalibrationSpec, RobotDescription


def _gyro_bias(s: SurfaceRun) -> None:
    s.bias = standstill_bias(s.tap, s.plan.gyro_still) if s.tap.gyro else None


def _accuracy_before(s: SurfaceRun) -> None:
    s.before = run_accuracy(s.runner, s.accuracy) if s.accuracy is not None else None


def _motor_map(s: SurfaceRun) -> None:
    if s.plan.motor_map:
        s.motors, s.balance = fit_motor_map(s.runner, s.plan, s.notes, s.stand)
        s.runner.motors = s.motors


def _deadbands(s: SurfaceRun) -> None:
    step, positions = s.plan.deadband_step, s.plan.deadband_positions
    s.deadbands = {
        f"course:{c:g}": find_deadband(s.runner, c, step, positions=positions).power
        for c in s.plan.calibrated_courses(s.geometry)
    }
    s.deadbands["rotation"] = find_deadband(s.runner, None, step, positions=positions).power


def _sweeps(s: SurfaceRun) -> None:
    for c in s.plan.calibrated_courses(s.geometry):
        s.straight += straight_sweep(s.runner, s.plan, c, s.deadbands[f"course:{c:g}"])


def _roller_drag(s: SurfaceRun) -> None:
    """The idle wheels' roller drag, fitted and taken out of the axis courses' sweeps."""
    plan, geometry = s.plan, s.geometry
    if not (
        plan.roller_rounds > 0 and all(geometry.roller_pitch) and s.source.can(RunInfo(STRAIGHT, "", 0.0))
    ):
        return
    axis = s.deadbands.get("course:0") or find_deadband(s.runner, 0.0, plan.deadband_step).power
    s.rollers = fit_rollers(geometry, roller_runs(s.runner, plan, axis, plan.roller_rounds))
    if s.rollers is None:
        s.notes.append("roller drag: the runs could not tell it (no drag term uploaded)")
    else:
        s.straight = correct_runs(geometry, s.rollers, s.straight)


def _rotation_sweep(s: SurfaceRun) -> None:
    s.rotation = rotation_sweep(s.runner, s.plan, s.deadbands["rotation"])


def _fit(s: SurfaceRun) -> None:
    """K, K_l and K_r from the sweeps; the section with the description's K_t, uploaded."""
    robot = s.robot
    fit = fit_surface(
        s.surface,
        s.straight,
        s.rotation,
        s.deadbands,
        s.geometry,
        move_length=s.plan.move_length,
        rotate_angle=s.plan.rotate_angle,
    )
    fit.motors, fit.balance, fit.rollers = s.motors, s.balance, s.rollers
    described = robot.calibration.k if robot.calibration is not None else None
    if described is not None and not 1 / 3 < fit.k / described < 3:
        s.notes.append(
            f"the fitted K ({fit.k:g}) is far from the description's ({described:g}): the runs may "
            "be too short for this robot (a heavy one coasts for long; try a longer --move-length) "
            "- check fig5_rates.png before using the tables"
        )
    s.fitted = fit
    s.section = build_spec([fit], robot, s.geometry, robot_table(robot, "k_t"))
    if s.upload:  # the steps after drive MOVEs through it
        s.client.upload_calibration(s.section)


def _turns(s: SurfaceRun) -> None:
    """Upload, then K_t from curved MOVEs (``plan.turn_rounds`` rounds, each uploaded): the last of the
    tables, after the reach, since nothing else the calibration drives uses K_t and so no other step
    starts from where the curved MOVEs leave the wheels (the idle wheels' drag depends on it)."""
    fit, spec = s.fit, s.spec
    if s.upload:
        s.client.upload_calibration(spec)
        for _ in range(s.plan.turn_rounds):
            turns = turning_runs(s.runner, s.plan, spec.k)
            new_kt = fit_kt(turns, spec.k_t)
            if new_kt is None:
                s.notes.append("no curved MOVE turned measurably: K_t kept")
                break
            spec = spec.model_copy(update={"k_t": new_kt})
            s.client.upload_calibration(spec)
    else:
        s.notes.append("not uploaded: K_t (measured with curved MOVEs) kept from the description")
    fit.kt = spec.k_t
    s.section = spec


def _roller_gains(s: SurfaceRun) -> None:
    spec = s.spec
    if s.upload and s.rollers is not None and spec.rollers is not None and spec.rollers.coast is not None:
        s.section = tune_rollers(s.runner, s.fit, spec, s.plan, s.notes)


def _slow_end(s: SurfaceRun) -> None:
    """K_l's slow end from MOVEs at the bottom of the speed range through the tables as they stand
    (:func:`~omnibot.calibration.fits.anchor_slow_end`); the new section, uploaded."""
    plan = s.plan
    if not (s.upload and plan.slow_rounds > 0 and s.source.can(RunInfo(STRAIGHT, "", 0.0))):
        return
    speed = round(speed_range(s.robot, plan.move_length)[0], 2)
    anchors = anchor_slow_end(s.fit, s.spec, s.geometry, slow_moves(s.runner, plan, speed), speed)
    if anchors:
        s.section = build_spec([s.fit], s.robot, s.geometry, s.spec.k_t)
        s.client.upload_calibration(s.section)


def _reach(s: SurfaceRun) -> None:
    """The reach: computed from the tables (PWM saturation), then, where the truth can measure straight
    runs and the tables are in the controller, MOVEs at it on the reach courses slowed until they land
    (:func:`~omnibot.calibration.reachmoves.measure_reach`); their reach goes into the section, uploaded."""
    plan, length = s.plan, s.plan.move_length
    top = speed_range(s.robot, length)[1]
    s.reach = reach = reach_speed(s.robot, s.spec, length)
    if s.upload and plan.reach_courses and s.source.can(RunInfo(STRAIGHT, "", 0.0)):
        s.reach_moves = measure = measure_reach(s.runner, s.spec, plan)
        table = measure.table
        if table is not None:
            s.section = s.spec.model_copy(update={"reach": table})
            s.client.upload_calibration(s.section)
            s.reach = min(table.speed)
            slowed = [
                f"{c:g} deg {measure.computed[c] or 0:g} -> {v:g} m/s"
                for c, v in zip(table.courses_deg, table.speed, strict=True)
                if v < min(measure.computed[c] or 0.0, top) - 1e-9
            ]
            s.notes.append(
                f"reach of {length:g} m MOVEs, driven: {describe_reach(table)} m/s"
                + (
                    f" (slower than the tables can power, where MOVEs fell short: {'; '.join(slowed)})"
                    if slowed
                    else ""
                )
                + "; the controller runs a MOVE asked faster at it (warning 18)"
            )
            return
        s.notes.append(
            "reach: on some course not even MOVEs at the bottom of the speed range landed within "
            f"{100 * plan.reach_goal:g} %: the calibration has no reach (the controller runs MOVEs as asked)"
        )
    if reach is None or reach < top:
        s.notes.append(
            f"MOVEs of {length:g} m reach "
            + ("no speed" if reach is None else f"{reach:g} m/s")
            + f" on every course with these tables (the robot's top: {top:g} m/s); faster ones "
            "saturate a motor (the controller warns 11, speed reduced) and fall short"
        )


def _rotation_test(s: SurfaceRun) -> None:
    if s.bias is not None:  # the bias wanders: measure it again right before the rotation test
        s.bias = standstill_bias(s.tap, s.plan.gyro_still) or s.bias
    s.rot_test = rotation_test(s.runner, s.plan)


def _gyro_scale(s: SurfaceRun) -> None:
    s.gyro = calibrate_gyro(s.bias, s.rot_test) if s.bias is not None else None


def _squares(s: SurfaceRun) -> None:
    if s.tap.odometry is not None and s.source.can(RunInfo(SQUARE, "")):
        plan, robot = s.plan, s.robot
        speed = plan.square_speed or round(0.5 * sum(speed_range(robot, plan.move_length)), 2)
        rate = rotation_test_rate(robot)
        s.squares = [drive_square(s.runner, plan.square_side, speed, rate, ccw) for ccw in (True, False)]


def _odometry(s: SurfaceRun) -> None:
    if s.tap.odometry is not None and s.source.exact:
        s.odometry = calibrate_odometry(s.robot, s.straight, s.rot_test, s.squares)
    elif s.tap.odometry is not None:
        s.notes.append(
            f"odometry corrections need an independent truth (sim, csv, tape), not {s.source.name}"
        )


def _accuracy_after(s: SurfaceRun) -> None:
    s.after = run_accuracy(s.runner, s.accuracy) if s.accuracy is not None and s.upload else None
    table = s.spec.reach
    if table is not None:
        checked = checked_reach_table(table, s.after or [], s.geometry.fold)
        if checked != table:
            s.notes.append(
                "the check's MOVEs within the driven reach were warned about (a motor short of power, or "
                "short on the encoders): the reach is "
                + ("none" if checked is None else f"{describe_reach(checked)} m/s")
            )
            s.section = s.spec.model_copy(update={"reach": checked})
            s.reach = None if checked is None else min(checked.speed)
        return
    reach = checked_reach(s.reach, s.after or [])
    if reach != s.reach:
        s.notes.append(
            f"the check's MOVEs at or below the computed reach ({s.reach:g} m/s) were warned about "
            "(a motor short of power, or short on the encoders): the reach is "
            + ("no speed checked" if reach is None else f"{reach:g} m/s")
        )
        s.reach = reach


@dataclass(frozen=True)
class Step:
    """One named step of a surface's calibration."""

    name: str
    run: Callable[[SurfaceRun], None]
    phase: str | None = None
    """The progress phase (:func:`expected_runs`) whose runs it drives; None: it drives none."""


STEPS: tuple[Step, ...] = (
    Step("gyro bias", _gyro_bias),
    Step("accuracy before", _accuracy_before, "before"),
    Step("motor map", _motor_map, "motor map"),
    Step("dead bands", _deadbands, "dead bands"),
    Step("straight sweeps", _sweeps, "sweeps"),
    Step("roller drag", _roller_drag, "roller drag"),
    Step("rotation sweep", _rotation_sweep, "rotation sweep"),
    Step("fit K, K_l, K_r", _fit),
    Step("roller gains", _roller_gains, "roller gains"),
    Step("slow end (K_l)", _slow_end, "slow end"),
    Step("reach", _reach, "reach"),
    Step("turns (K_t)", _turns, "turns"),
    Step("rotation test", _rotation_test, "rotation test"),
    Step("gyro scale", _gyro_scale),
    Step("squares", _squares, "squares"),
    Step("odometry", _odometry),
    Step("accuracy after", _accuracy_after, "after"),
)
"""A surface's calibration, in order. Every phase of :func:`expected_runs` is one step's, so when
the last step ends the progress bar's total is the runs driven."""


def tune_rollers(
    runner: Runner, fit: SurfaceFit, spec: CalibrationSpec, plan: Plan, notes: list[str]
) -> CalibrationSpec:
    """The roller drag's coast from MOVEs and the motor axes' offsets evened out by the same MOVEs
    (rollers.py); the new section, uploaded. ``fit`` gets the coast and the shifted motor map."""
    robot, geometry = runner.robot, runner.geometry
    assert fit.rollers is not None
    bottom, top = speed_range(robot, plan.move_length)
    # up to 90 % of the reach of the courses the MOVEs drive (the motor axes; at the reach itself a
    # motor runs out of power at the worst wheel position, which no gain can make up for). Not every
    # course's: the axes' reach is the faster, and the controller holds the coast of the fastest
    # speed beyond it, so MOVEs on the axes up to their reach need it measured there
    reach = reach_speed(robot, spec, plan.move_length, axis_courses(geometry))
    fastest = max(bottom, 0.9 * min(top, reach or top))
    speeds = sorted({round(bottom + (fastest - bottom) * k / 3, 2) for k in range(4)})
    fit.coast = tune_coast(
        runner, spec, fit.rollers, speeds, plan.move_length, plan.roller_rounds, plan.coast_slow_rounds
    )
    if fit.coast is None:
        notes.append("roller drag: the MOVEs could not tell its coast; the drag runs' own is kept")
        return spec
    if fit.motors is not None:
        shift = offset_shift(geometry, fit.coast.ahead)
        offsets = tuple(max(0.0, round(o + d, 1)) for o, d in zip(fit.motors.offset, shift, strict=True))
        fit.motors = fit.motors.model_copy(update={"offset": offsets})
        runner.motors = fit.motors
    spec = build_spec([fit], robot, geometry, spec.k_t)
    runner.client.upload_calibration(spec)
    return spec


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
