"""The whole calibration of one robot: per surface, then averaged over the surfaces.

Per surface (:func:`calibrate_surface`), on one client, the named steps of :data:`STEPS` in order,
each reading and filling in one :class:`SurfaceRun`::

    gyro bias (standstill) -> accuracy before -> motor map -> dead bands -> straight sweeps
    -> roller drag -> rotation sweep -> fit K, K_l, K_r, upload
    -> roller gains: the drag's coast from MOVEs, upload -> slow end: K_l from MOVEs, upload
    -> reach: MOVEs at the computed reach per course, slowed until they land, upload
    -> turns: curved MOVEs, fit K_t, upload -> rotation test -> gyro scale -> squares CCW and CW (UMBmark) -> odometry corrections -> accuracy after
    then the wheel slip (its own progress bar)

Over surfaces (:func:`calibrate`): each surface as above, then the averaged calibration (seed 000
averaged wood and carpet), uploaded and checked on every surface again. The results are
:mod:`omnibot.calibration.results`' types.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager
from dataclasses import dataclass, field
from functools import partial

from omnibot.calibration.accuracy import (
    AccuracyPlan,
    AccuracyRow,
    ReachMeasure,
    checked_reach,
    checked_reach_table,
    describe_reach,
    lowest_reach,
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
    average_kt,
    build_spec,
    fit_kt,
    fit_surface,
    robot_table,
)
from omnibot.calibration.gyro import GyroCalibration, calibrate_gyro
from omnibot.calibration.motorfit import (
    STAND_POWERS,
    Balance,
    balance_courses,
    identity,
    offsets_from_deadbands,
)
from omnibot.calibration.motors import MODEL_ROUNDS, balance_model, motor_deadbands, stand_test
from omnibot.calibration.patterns import Geometry, top_power
from omnibot.calibration.plan import Plan, speed_range
from omnibot.calibration.reachmoves import measure_reach, phase_count
from omnibot.calibration.results import CalibrationResult, SurfaceSession
from omnibot.calibration.rollerfit import RollerFit, axis_courses, correct_runs, fit_rollers, offset_shift
from omnibot.calibration.rollers import SHARES, roller_runs, tune_coast
from omnibot.calibration.runner import Runner
from omnibot.calibration.runs import ROTATE, SQUARE, STRAIGHT, RunInfo, RunResult
from omnibot.calibration.slip import slip_step
from omnibot.calibration.tap import TelemetryTap, standstill_bias
from omnibot.calibration.truth import Ask, TruthContext, TruthSource, make_truth, simulator_of
from omnibot.calibration.umbmark import OdometryCalibration, SquareRun, calibrate_odometry
from omnibot.calibration.verdict import judge_average
from omnibot.client import RobotClient
from omnibot.errors import ConfigError
from omnibot.firmware.config import build_config
from omnibot.navigation import SLIP_COURSES, SlipCalibration
from omnibot.progress import Progress
from omnibot.protocol import codes
from omnibot.robot import CalibrationSpec, MotorMapSpec, RobotDescription
from omnibot.runtime import RuntimeRecording

ProgressFactory = Callable[[str, int], AbstractContextManager[Progress | None]]
"""(description, expected runs) -> a context giving a progress bar (or None)."""

Lift = Callable[[RobotClient, bool], None]
"""Puts the robot on a stand, every wheel off the floor (True), and back where it stood (False)."""


@contextmanager
def no_progress(desc: str, total: int) -> Iterator[Progress | None]:
    """A progress context that shows nothing (yields None)."""
    yield None


def accuracy_runs(accuracy: AccuracyPlan, robot: RobotDescription) -> int:
    """The runs of one accuracy check (:func:`~omnibot.calibration.check.run_accuracy`)."""
    moves = len(accuracy.courses_deg) * len(accuracy.move_speeds(robot)) * (2 if accuracy.back else 1)
    return moves + 2 * len(accuracy.rotations)


DEADBAND_RUNS = 10
"""Runs a dead-band search takes, about (a sweep upward in ``deadband_step`` counts, then bisection)."""
DEADBAND_AGAIN = 5
"""Runs a dead band takes at each further wheel position, about (the ROTATE and a bracketed search)."""


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
    # each power through the offsets and once per motor (its Jacobian), then each Gauss-Newton step
    balance = len(balance_courses(geometry)) * ((1 + geometry.motors) * powers + MODEL_ROUNDS * powers)
    balance += len(STAND_POWERS) if robot.has_wheel_encoders else 0  # the stand test, where it can run
    rollers = plan.roller_rounds > 0 and all(geometry.roller_pitch)
    axes = len(axis_courses(geometry))
    again = (max(1, plan.deadband_positions) - 1) * DEADBAND_AGAIN  # each further wheel position
    phases = {
        "before": checks,
        "motor map": (1 + geometry.motors) * (DEADBAND_RUNS + again) + balance if plan.motor_map else 0,
        "dead bands": (courses + 1) * ((3 if plan.motor_map else DEADBAND_RUNS) + again),
        "sweeps": courses * plan.levels * plan.directions * 2,
        "roller drag": len(SHARES) * (1 + plan.roller_rounds * axes) if rollers else 0,
        "rotation sweep": plan.levels * 2 * 2,
        # each MOVE and the ROTATE before it that sets the idle wheels' phase (most MOVEs need one)
        "roller gains": 2 * (3 * plan.roller_rounds + plan.coast_slow_rounds) * axes
        if rollers and upload
        else 0,
        "slow end": courses * plan.directions * plan.slow_rounds if upload else 0,
        "reach": sum(
            (len(geometry.every_raw_course(f)) + 1) * phase_count(geometry, f, plan) - 1
            for f in plan.reach_folds(geometry)
        )
        if upload
        else 0,
        "turns": plan.turn_rounds * len(plan.turn_curvatures) * len(plan.turn_courses_deg) * 2
        if upload
        else 0,
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
        """The bar's total: runs done plus the runs still expected of the phases to come."""
        return self.runs + sum(self.left.values())

    def update(self, n: float | None = 1) -> bool | None:
        """Count ``n`` runs done."""
        self.runs += int(n or 0)
        return self.bar.update(n) if self.bar is not None else None

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        """Show ``s`` after the bar."""
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
        """Give the bar its current :attr:`total` and redraw it."""
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


@dataclass
class SurfaceRun:
    """One surface's calibration in progress: what its steps share and what they found so far."""

    surface: str
    plan: Plan
    accuracy: AccuracyPlan | None
    upload: bool
    runner: Runner
    stand: Lift | None = None
    """How to put the robot on a stand where the link has no simulator (None: nobody can)."""
    notes: list[str] = field(default_factory=list)
    bias: tuple[float, float, int] | None = None
    """The gyro's standstill bias (mean, its standard error, samples)."""
    before: list[AccuracyRow] | None = None
    motors: MotorMapSpec | None = None
    balance: Balance | None = None
    deadbands: dict[str, int] = field(default_factory=dict)
    straight: list[RunResult] = field(default_factory=list)
    rollers: RollerFit | None = None
    rotation: list[RunResult] = field(default_factory=list)
    fitted: SurfaceFit | None = None
    section: CalibrationSpec | None = None
    """The calibration section as it stands (uploaded when ``upload``)."""
    reach: float | None = None
    """m/s: the slowest course's reach (the section's ``reach`` table; else computed)."""
    reach_moves: ReachMeasure | None = None
    rot_test: list[RunResult] = field(default_factory=list)
    gyro: GyroCalibration | None = None
    squares: list[SquareRun] = field(default_factory=list)
    odometry: OdometryCalibration | None = None
    after: list[AccuracyRow] | None = None
    slip: SlipCalibration | None = None
    recording: RuntimeRecording | None = None
    """The command's ``--log``: records the slip runs' runtime."""

    @property
    def client(self) -> RobotClient:
        """The runner's robot client."""
        return self.runner.client

    @property
    def robot(self) -> RobotDescription:
        """The robot being calibrated."""
        return self.runner.robot

    @property
    def geometry(self) -> Geometry:
        """The robot's geometry as the firmware sees it."""
        return self.runner.geometry

    @property
    def tap(self) -> TelemetryTap:
        """The runner's telemetry tap."""
        return self.runner.tap

    @property
    def source(self) -> TruthSource:
        """The ground truth the runs are measured by."""
        return self.runner.truth

    @property
    def fit(self) -> SurfaceFit:
        """The surface's fit (AssertionError before the fit step)."""
        assert self.fitted is not None, "the fit step has not run"
        return self.fitted

    @property
    def spec(self) -> CalibrationSpec:
        """The calibration section as it stands (AssertionError before the fit step)."""
        assert self.section is not None, "the fit step has not run"
        return self.section

    def session(self) -> SurfaceSession:
        """The surface's result."""
        return SurfaceSession(
            surface=self.surface,
            truth=self.source.describe(),
            fit=self.fit,
            spec=self.spec,
            runs=self.runner.log,
            gyro=self.gyro,
            odometry=self.odometry,
            before=self.before,
            after=self.after,
            notes=self.notes,
            slip=self.slip,
            reach=self.reach,
            reach_moves=self.reach_moves,
        )


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
    stand: Lift | None = None,
    recording: RuntimeRecording | None = None,
) -> SurfaceSession:
    """Measure, fit and (``upload``) apply the calibration of ``robot`` on one surface: :data:`STEPS`,
    then the wheel slip (its runtime recorded in ``recording``)."""
    plan = plan or Plan()
    phases = expected_runs(plan, Geometry.of(robot), accuracy, robot, upload)  # checks the courses
    client.stop()
    _open_loop(client)
    tap = TelemetryTap(client, robot)
    tap.start()
    source = make_truth(truth, TruthContext(client, robot, tap, ask))
    with progress(f"calibrate {robot.name} on {surface}", sum(phases.values())) as bar:
        tally = Tally(bar, phases)
        runner = Runner(client, robot, source, tap, settle=plan.settle, progress=tally)
        state = SurfaceRun(surface, plan, accuracy, upload, runner, stand, recording=recording)
        try:
            for step in STEPS:
                step.run(state)
                if step.phase is not None:
                    tally.done(step.phase)
        finally:
            runner.close()
            tap.stop()
    _wheel_slip(state, progress)
    return state.session()


def _wheel_slip(s: SurfaceRun, progress: ProgressFactory) -> None:
    """The floor's wheel slip (its own runs, wheel-speed loop on), when the robot has wheel encoders
    and the truth is independent of them; the controller back in open loop after."""
    client = s.client
    if not (s.plan.slip and s.tap.odometry is not None):
        return
    if not s.source.exact:
        s.notes.append(f"wheel slip needs an independent truth (sim, csv, tape), not {s.source.name}")
        return
    with progress(f"wheel slip on {s.surface}", SLIP_COURSES) as slip_bar:
        try:
            s.slip = slip_step(client, s.robot, s.source, slip_bar, recording=s.recording)
        except ConfigError as exc:
            s.notes.append(f"wheel slip not calibrated: {exc}")
        finally:  # back to what the rest of the calibration expects (the runs end stopped)
            if client.binary:
                client.use_text()
            _open_loop(client)


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
    stand: Lift | None = None,
    recording: RuntimeRecording | None = None,
) -> CalibrationResult:
    """Calibrate on every surface (``stand``: how to lift a robot that is not simulated, for the motor
    map's stand test; ``recording``: the command's ``--log``, for the runtimes it runs), then average and check the average on every surface (it is kept
    only when it is better than none on every one: :attr:`CalibrationResult.average_better`)."""
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
                    stand=stand,
                    recording=recording,
                )
            )
    result = CalibrationResult(robot, sessions)
    if len(sessions) > 1:
        geometry = Geometry.of(robot)
        fits = [s.fit for s in sessions]
        result.average = build_spec(fits, robot, geometry, average_kt(fits))
        reach = lowest_reach([s.spec.reach for s in sessions])  # the slower floor's on every course
        if reach is not None:
            result.average = result.average.model_copy(update={"reach": reach})
        if accuracy is not None and upload:
            _check_average(result, surfaces, open_client, truth_for, accuracy, ask, progress)
    return result


def _check_average(
    result: CalibrationResult,
    surfaces: list[str],
    open_client: ClientOpener,
    truth_for: Callable[[RobotClient], str],
    accuracy: AccuracyPlan,
    ask: Ask,
    progress: ProgressFactory,
) -> None:
    """:func:`calibrate`'s check of ``result.average`` on every surface, and whether it is kept."""
    assert result.average is not None
    for surface in surfaces:
        with (
            open_client(surface) as client,
            progress(f"check the average on {surface}", accuracy_runs(accuracy, result.robot)) as bar,
        ):
            result.average_checks[surface] = check_average(
                client,
                result.robot,
                result.average,
                truth=truth_for(client),
                accuracy=accuracy,
                ask=ask,
                progress=bar,
            )
    average = judge_average(result)
    result.average_better = None if average is None else average.better
