"""Open-loop accuracy: what the check measures, its rows and summary, and a calibration's reach
(plain data and the firmware's power model, no I/O; :mod:`omnibot.calibration.check` drives it).

Run before and after uploading a calibration, the check is the before/after table of the report.
Each MOVE on course ``c`` is followed by one back on ``c + 180`` (so the robot stays near its
start); both are rows. Errors: distance (achieved / commanded - 1), course (direction of the
displacement against the commanded course, degrees) and heading (how far the body turned, degrees;
a straight MOVE should not turn it). For ROTATE the error is the angle's.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

from omnibot.calibration.plan import speed_range
from omnibot.firmware.calibration import Calibration
from omnibot.firmware.config import build_config
from omnibot.firmware.power import PowerModel
from omnibot.robot import CalibrationSpec, ReachSpec, RobotDescription

REACH_COURSES = tuple(float(c) for c in range(0, 360, 15))
"""Courses (degrees) :func:`reach_speed` checks."""


@dataclass(frozen=True)
class AccuracyPlan:
    """What an accuracy check drives: MOVEs on each course at each speed (and back), and ROTATEs."""

    courses_deg: tuple[float, ...] = (0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0)
    speeds: tuple[float, ...] | None = None
    """m/s; default: four from the lowest speed to 90 % of the highest of :func:`speed_range`."""
    length: float = 1.0
    back: bool = True
    rotations: tuple[tuple[float, float], ...] = ((90.0, 90.0), (180.0, 180.0))
    """(angle, rate) in degrees and degrees/s, each both ways."""

    def move_speeds(self, robot: RobotDescription) -> list[float]:
        """The MOVE speeds for ``robot``, m/s: :attr:`speeds`, else four from the lowest to 90 % of the
        highest."""
        if self.speeds is not None:
            return list(self.speeds)
        lo, hi = speed_range(robot, self.length)
        hi *= 0.9
        return [round(lo + (hi - lo) * k / 3, 2) for k in range(4)]

    @classmethod
    def quick(cls) -> AccuracyPlan:
        """A short check: courses 0, 45 and 90 degrees, one rotation."""
        return cls(courses_deg=(0.0, 45.0, 90.0), speeds=None, rotations=((90.0, 90.0),))


@dataclass(frozen=True)
class AccuracyRow:
    """One run of an accuracy check: what was commanded and what was achieved, with its errors."""

    kind: str
    """``move`` or ``rotate``."""
    course_deg: float
    speed: float
    """m/s (move) or degrees/s (rotate)."""
    commanded: float
    """m (move) or degrees (rotate), signed for rotations."""
    achieved: float | None
    error: float | None
    """achieved / commanded - 1."""
    course_error_deg: float | None = None
    heading_error_deg: float | None = None
    source: str = ""
    saturated: bool = False
    """The controller warned that the motors could not give the power asked (warning 11, speed reduced)."""
    short: bool = False
    """The controller warned that the MOVE stood still short of its distance on its wheel encoders
    (warning 17)."""
    clamped: bool = False
    """The controller warned that it ran the MOVE at the calibrated reach, slower than asked (warning
    18)."""

    @property
    def warned(self) -> bool:
        """The controller warned about this run (warning 11 or 17)."""
        return self.saturated or self.short

    def as_dict(self) -> dict[str, Any]:
        """The row as plain data (for the JSON report)."""
        return asdict(self)


def reach_speed(
    robot: RobotDescription,
    spec: CalibrationSpec,
    length: float,
    courses_deg: Sequence[float] = REACH_COURSES,
) -> float | None:
    """m/s: the fastest MOVE of ``length`` that the calibration can power on every course without a
    motor saturating, the roller drag counted at its worst phase; None when not even the slowest can.

    The powers are the firmware's own (:class:`~omnibot.firmware.power.PowerModel` on the calibrated
    description), from the robot's slowest MOVE up to its fastest in 1 cm/s steps.
    """
    cfg = build_config(robot.model_copy(update={"calibration": spec}))
    model = PowerModel(cfg, Calibration(cfg))
    cal, n, pwm_max = model.cal, model.n, model.pwm_max
    lo, hi = speed_range(robot, length)
    out = [0] * n
    best = None
    for step in range(round(100 * lo), round(100 * hi) + 1):
        v = step / 100.0
        gain = 1.0 + cal.coast(100.0 * v) * v / length
        for course in courses_deg:
            ux, uy = math.cos(math.radians(course)), math.sin(math.radians(course))
            model.compute(v * ux, v * uy, 0.0, False, out)
            along = [r[0] * ux + r[1] * uy for r in model.rim]
            busiest = max(abs(a) for a in along)
            worst = gain * sum(
                math.hypot(cal.roller_cos[i], cal.roller_sin[i]) * abs(d[0] * ux + d[1] * uy)
                for i, d in enumerate(model.roller_dir)
                if model.roller_pitch[i] > 0.0
            )
            if any(abs(model.base[i]) + worst * abs(along[i]) / busiest > pwm_max for i in range(n)):
                return best
        best = v
    return best


def checked_reach(reach: float | None, rows: Sequence[AccuracyRow]) -> float | None:
    """``reach`` (:func:`reach_speed`) lowered to what the check's MOVEs showed: when the controller
    warned about a MOVE at or below it (warning 11 or 17: a motor could not give the power, or the MOVE
    fell short on its encoders), the fastest speed the check drove below the slowest such MOVE without a
    warning on any course (None when there is none). A MOVE the controller ran at the reach (warning
    18) counts at the speed it ran, the reach."""
    if reach is None:
        return None
    moves = [r for r in rows if r.kind == "move"]
    warned = [min(r.speed, reach) if r.clamped else r.speed for r in moves if r.warned]
    warned = [v for v in warned if v <= reach]
    if not warned:
        return reach
    slowest = min(warned)
    clean = [r.speed for r in moves if r.speed < slowest]
    return max(clean) if clean else None


def checked_reach_table(
    reach: ReachSpec | None, rows: Sequence[AccuracyRow], fold: Callable[[float], float]
) -> ReachSpec | None:
    """:func:`checked_reach` on each course of a reach table, with the check's MOVEs whose folded
    course (``fold``) is nearest to it; None when a course keeps no speed."""
    if reach is None:
        return None
    courses = reach.courses_deg
    groups: dict[float, list[AccuracyRow]] = {c: [] for c in courses}
    for r in rows:
        if r.kind == "move":
            f = fold(r.course_deg)
            groups[min(courses, key=lambda c: abs(c - f))].append(r)
    speeds = [checked_reach(v, groups[c]) for c, v in zip(courses, reach.speed, strict=True)]
    if any(v is None for v in speeds):
        return None
    return ReachSpec(courses_deg=courses, speed=tuple(v for v in speeds if v is not None))


def lowest_reach(tables: Sequence[ReachSpec | None]) -> ReachSpec | None:
    """The slowest of several reach tables on every course of their union (None if any has none)."""
    if not tables or any(t is None for t in tables):
        return None
    known = [t for t in tables if t is not None]
    courses = sorted({c for t in known for c in t.courses_deg})
    return ReachSpec(courses_deg=tuple(courses), speed=tuple(min(t(c) for t in known) for c in courses))


def describe_reach(reach: ReachSpec) -> str:
    """A reach table as text: ``0 deg 1, 15 deg 0.76, ...`` (m/s)."""
    return ", ".join(f"{c:g} deg {v:g}" for c, v in zip(reach.courses_deg, reach.speed, strict=True))


def within_reach(row: AccuracyRow, reach: ReachSpec | None, fold: Callable[[float], float]) -> bool:
    """A MOVE of the check asked no faster than the reach on its course (False without a reach)."""
    return reach is not None and row.speed <= reach(fold(row.course_deg)) + 1e-9


@dataclass
class ReachMeasure:
    """What :func:`measure_reach` found."""

    computed: dict[float, float | None] = field(default_factory=dict)
    """Per folded course, the reach the tables can power (m/s, :func:`reach_speed`)."""
    measured: dict[float, float | None] = field(default_factory=dict)
    """Per folded course, the fastest speed at which every MOVE landed (None: not even the bottom of
    the speed range)."""
    rows: list[AccuracyRow] = field(default_factory=list)
    """Every reach MOVE, in the order driven."""

    @property
    def table(self) -> ReachSpec | None:
        """The reach per folded course; None when a course has none."""
        speeds = [self.measured[c] for c in sorted(self.measured)]
        if not speeds or any(v is None for v in speeds):
            return None
        return ReachSpec(
            courses_deg=tuple(sorted(self.measured)), speed=tuple(v for v in speeds if v is not None)
        )


@dataclass(frozen=True)
class Summary:
    """Mean and largest absolute errors of a set of rows."""

    moves: int
    distance_mean: float | None
    distance_max: float | None
    heading_mean_deg: float | None
    heading_max_deg: float | None
    course_mean_deg: float | None
    course_max_deg: float | None
    rotate_mean: float | None
    rotate_max: float | None

    def as_dict(self) -> dict[str, Any]:
        """The summary as plain data (for the JSON report)."""
        return asdict(self)


def _stats(values: Sequence[float | None]) -> tuple[float | None, float | None]:
    v = [abs(x) for x in values if x is not None]
    return (statistics.fmean(v), max(v)) if v else (None, None)


def summarize(rows: Sequence[AccuracyRow]) -> Summary:
    """Mean and largest absolute distance, heading and course errors of the MOVEs and ROTATEs in ``rows``."""
    moves = [r for r in rows if r.kind == "move"]
    rot = [r for r in rows if r.kind == "rotate"]
    dm, dx = _stats([r.error for r in moves])
    hm, hx = _stats([r.heading_error_deg for r in moves])
    cm, cx = _stats([r.course_error_deg for r in moves])
    rm, rx = _stats([r.error for r in rot])
    return Summary(len(moves), dm, dx, hm, hx, cm, cx, rm, rx)
