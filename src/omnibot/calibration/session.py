"""The whole calibration of one robot: per surface, then averaged over the surfaces.

Per surface (:func:`calibrate_surface`), on one client, the named steps of
:data:`~omnibot.calibration.steps.STEPS` in order, each reading and filling in one
:class:`~omnibot.calibration.surface_run.SurfaceRun`, the progress bar's total kept by
:class:`~omnibot.calibration.tally.Tally`::

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

from collections.abc import Callable
from contextlib import AbstractContextManager

from omnibot.calibration.accuracy import (
    AccuracyPlan,
    AccuracyRow,
    lowest_reach,
)
from omnibot.calibration.check import run_accuracy
from omnibot.calibration.fits import (
    average_kt,
    build_spec,
)
from omnibot.calibration.motors import Lift
from omnibot.calibration.patterns import Geometry
from omnibot.calibration.plan import Plan
from omnibot.calibration.results import CalibrationResult, SurfaceSession
from omnibot.calibration.runner import Runner
from omnibot.calibration.slip import slip_step
from omnibot.calibration.steps import STEPS
from omnibot.calibration.surface_run import SurfaceRun
from omnibot.calibration.tally import ProgressFactory, Tally, accuracy_runs, expected_runs, no_progress
from omnibot.calibration.tap import TelemetryTap
from omnibot.calibration.truth import Ask, TruthContext, make_truth
from omnibot.calibration.verdict import judge_average
from omnibot.client import RobotClient
from omnibot.errors import ConfigError
from omnibot.navigation import SLIP_COURSES
from omnibot.progress import Progress
from omnibot.protocol import codes
from omnibot.robot import CalibrationSpec, RobotDescription
from omnibot.runtime import RuntimeRecording


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
