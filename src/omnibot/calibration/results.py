"""What a calibration produced: each surface's :class:`SurfaceSession` and the whole
:class:`CalibrationResult` (plain data, no I/O; :mod:`omnibot.calibration.session` fills them in,
:mod:`omnibot.calibration.calfile`, :mod:`omnibot.calibration.report` and
:mod:`omnibot.calibration.verdict` read them)."""

from __future__ import annotations

import statistics
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from omnibot.calibration.accuracy import AccuracyRow, ReachMeasure
from omnibot.calibration.fits import SurfaceFit
from omnibot.calibration.gyro import GyroCalibration
from omnibot.calibration.runs import RunResult
from omnibot.calibration.umbmark import OdometryCalibration
from omnibot.robot import CalibrationSpec, RobotDescription

if TYPE_CHECKING:  # the slip fit's result type only (navigation.slipcal drives the runs)
    from omnibot.navigation import SlipCalibration


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
    """m/s: the slowest course's reach, where MOVEs of the reference length land on every course (the
    section's ``reach`` table, driven); without one, the fastest the tables power on every course
    (:func:`~omnibot.calibration.accuracy.reach_speed`)."""
    reach_moves: ReachMeasure | None = None
    """The reach MOVEs (:func:`~omnibot.calibration.reachmoves.measure_reach`), when they were driven."""


@dataclass
class CalibrationResult:
    """A whole calibration: the robot, one session per surface and the average over the surfaces with its
    checks."""

    robot: RobotDescription
    sessions: list[SurfaceSession]
    average: CalibrationSpec | None = None
    """The tables averaged over the surfaces (seed 000's), when there are several."""
    average_checks: dict[str, list[AccuracyRow]] = field(default_factory=dict)
    """The accuracy check of :attr:`average` on each surface."""
    average_better: bool | None = None
    """Its verdict (:func:`~omnibot.calibration.verdict.judge_average`): False when it is worse than
    no calibration on some surface, None when it was not checked."""

    @property
    def chosen(self) -> CalibrationSpec | None:
        """The tables for a robot that does not say which floor it stands on: the one surface's, or
        the average over several unless its check found it worse than none on one of them (then
        None: each floor keeps only its own, :attr:`SurfaceSession.spec`)."""
        if self.average is None:
            return self.sessions[0].spec if len(self.sessions) == 1 else None
        return None if self.average_better is False else self.average

    @property
    def gyro(self) -> GyroCalibration | None:
        """The gyro over all sessions: the last bias, the mean scale; None when no session calibrated it."""
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
        """The odometry geometry over all sessions (scales averaged); None when no session calibrated it."""
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
