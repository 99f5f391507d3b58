"""What one surface's calibration steps share: :class:`SurfaceRun`, filled in step by step."""

from __future__ import annotations

from dataclasses import dataclass, field

from omnibot.calibration.accuracy import (
    AccuracyPlan,
    AccuracyRow,
    ReachMeasure,
)
from omnibot.calibration.fits import (
    SurfaceFit,
)
from omnibot.calibration.gyro import GyroCalibration
from omnibot.calibration.motorfit import (
    Balance,
)
from omnibot.calibration.motors import Lift
from omnibot.calibration.patterns import Geometry
from omnibot.calibration.plan import Plan
from omnibot.calibration.results import SurfaceSession
from omnibot.calibration.rollerfit import RollerFit
from omnibot.calibration.runner import Runner
from omnibot.calibration.runs import RunResult
from omnibot.calibration.tap import TelemetryTap
from omnibot.calibration.truth import TruthSource
from omnibot.calibration.umbmark import OdometryCalibration, SquareRun
from omnibot.client import RobotClient
from omnibot.navigation import SlipCalibration
from omnibot.robot import CalibrationSpec, MotorMapSpec, RobotDescription
from omnibot.runtime import RuntimeRecording


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
