"""Fits of seed 000's calibration functions from measured runs (pure functions, no I/O).

The firmware turns a requested motion into power as ``P = K * f(p) * rim speed`` where ``p = K *
(busiest wheel's rim speed)`` is the uncalibrated power and ``f`` is K_l(p, course) for translation,
K_r(p) for rotation in place and K_t(p) for the turning of a curved MOVE (docs/firmware.md). So
``f(p)`` must be the power that really gives the rim speed ``p / K``, divided by ``p``.

From the runs of one power level each level's steady rate, start/stop loss and *effective* rate for
moves of the reference length, then the curve of rim speed against power they make
(:class:`~omnibot.calibration.rates.RateCurve`: monotone, anchored at the dead band, inverted) are
:mod:`omnibot.calibration.rates`'. The factor tables sample ``power_for(p / K) / p`` at integer
knots spaced geometrically over the powers the robot's speed range needs (the factor is close to
``a / p + b``, so knots dense at low power keep the linear interpolation within a fraction of a
percent). Averaging over surfaces averages the power needed for the same uncalibrated power, as
seed 000 averaged wood and carpet.

K_t is fitted from curved MOVEs instead: the body's turn against the commanded one gives the ratio
by which the factor in use was off, ``K_t,new(p) = K_t,old(p) / ratio`` (run twice, it converges).
"""

from __future__ import annotations

import math
import statistics
from collections import defaultdict
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

from omnibot.calibration.coastfit import CoastTuning
from omnibot.calibration.motorfit import Balance
from omnibot.calibration.patterns import Geometry
from omnibot.calibration.plan import speed_range
from omnibot.calibration.rates import RateCurve, RatePoint, rate_points
from omnibot.calibration.rollerfit import RollerFit
from omnibot.calibration.runs import RunResult
from omnibot.errors import ConfigError
from omnibot.robot import (
    CalibrationSpec,
    CourseTable,
    MotorMapSpec,
    PiecewiseLinear,
    RobotDescription,
    RollerDragSpec,
)

KNOTS = 14
"""Geometric knots over the working range (plus full power): the protocol allows 16."""
FACTOR_MAX = 30.0
"""Largest factor kept (the protocol's x1000 integers end at 32.767)."""


def knot_powers(low: float, high: float, pwm_max: int, count: int = KNOTS) -> tuple[int, ...]:
    """Integer powers spaced geometrically from ``low`` to ``high`` (plus ``pwm_max``), increasing."""
    lo = max(1.0, min(low, pwm_max - 1.0))
    hi = min(max(high, lo + 1.0), float(pwm_max))
    out: list[int] = []
    for k in range(count):
        p = round(lo * (hi / lo) ** (k / (count - 1)))
        if not out or p > out[-1]:
            out.append(p)
    if out[-1] < pwm_max:
        out.append(pwm_max)
    return tuple(out)


def factor_table(curves: Sequence[RateCurve], k: float, knots: Sequence[int]) -> PiecewiseLinear:
    """``power_for(p / K) / p`` at each knot, averaged over curves (surfaces), rounded as CAL sends it."""
    ys = []
    for p in knots:
        needed = statistics.fmean(c.power_for(p / k) for c in curves)
        ys.append(round(min(max(needed / p, 1e-3), FACTOR_MAX), 3))
    return PiecewiseLinear(x=tuple(float(p) for p in knots), y=tuple(ys))


def translation_knots(
    robot: RobotDescription, geometry: Geometry, k: float, courses: Sequence[float], length: float = 1.0
) -> tuple[int, ...]:
    """Power knots (PWM counts) of the translation sweeps: from 0.7 of the power the slowest speed
    needs on the course that needs least to 1.15 of what the fastest needs on the one that needs most."""
    slow, fast = speed_range(robot, length)
    factors = [geometry.translation_factor(c) for c in courses]
    return knot_powers(0.7 * k * slow * min(factors), 1.15 * k * fast * max(factors), geometry.pwm_max)


def rotation_knots(robot: RobotDescription, geometry: Geometry, k: float) -> tuple[int, ...]:
    """Power knots (PWM counts) of the rotation sweeps, from 0.2 rad/s to the robot's top turn rate."""
    rot = geometry.rotation_factor()
    return knot_powers(k * rot * 0.2, k * rot * robot.limits.angular_speed_max, geometry.pwm_max)


def fit_kt(runs: Iterable[RunResult], current: PiecewiseLinear | None) -> PiecewiseLinear | None:
    """K_t from curved MOVEs (see the module docstring); None when no run turned measurably."""
    by_p: dict[int, list[float]] = defaultdict(list)
    for r in runs:
        a = r.amount
        if r.p_arg is None or r.commanded is None or a is None or r.commanded <= 0:
            continue
        by_p[max(1, round(r.p_arg))].append(a / r.commanded)
    xs, ys = [], []
    for p in sorted(by_p):
        ratio = statistics.fmean(by_p[p])
        if ratio < 0.05:
            continue
        old = current(p) if current is not None else 1.0
        xs.append(float(p))
        ys.append(round(min(max(old / ratio, 0.05), FACTOR_MAX), 3))
    if not xs:
        return None
    return PiecewiseLinear(x=tuple(xs), y=tuple(ys))


def average_tables(tables: Sequence[PiecewiseLinear]) -> PiecewiseLinear:
    """The mean of piecewise-linear tables, on the union of their knots."""
    xs = sorted({x for t in tables for x in t.x})
    return PiecewiseLinear(x=tuple(xs), y=tuple(round(statistics.fmean(t(x) for t in tables), 3) for x in xs))


# --------------------------------------------------------------------------- per surface


@dataclass
class SurfaceFit:
    """Everything fitted on one surface; :meth:`spec` is its calibration section."""

    surface: str
    k: float
    courses: tuple[float, ...]
    translation: dict[float, RateCurve]
    rotation: RateCurve | None
    points: dict[str, list[RatePoint]] = field(default_factory=dict)
    deadbands: dict[str, int] = field(default_factory=dict)
    kt: PiecewiseLinear | None = None
    move_length: float = 1.0
    motors: MotorMapSpec | None = None
    """The motor map the sweeps ran through (their powers are nominal)."""
    balance: Balance | None = None
    """The balance runs' outcome, for the report."""
    rollers: RollerFit | None = None
    """The idle wheels' roller drag (its runs were taken out of the axis-course sweeps)."""
    coast: CoastTuning | None = None
    """The roller drag's coast table as MOVEs measured it (replaces the drag runs' own)."""
    anchors: dict[float, SlowAnchor] = field(default_factory=dict)
    """Per calibrated course, the slow end's point measured with MOVEs (:func:`anchor_slow_end`)."""

    @property
    def roller_spec(self) -> RollerDragSpec | None:
        """The roller drag section: the fit's, with the MOVEs' coast table and drag coefficients when
        they measured them."""
        if self.rollers is None:
            return None
        spec = self.rollers.spec
        if self.coast is not None and spec.coast is not None:
            spec = spec.model_copy(update={"coast": self.coast.table})
            if self.coast.cos is not None and self.coast.sin is not None:
                spec = spec.model_copy(update={"cos": self.coast.cos, "sin": self.coast.sin})
        return spec


@dataclass(frozen=True)
class SlowAnchor:
    """One calibrated course's MOVEs at the bottom of the speed range (:func:`anchor_slow_end`)."""

    speed: float
    """m/s commanded."""
    power: float
    """The nominal power of the busiest motor the tables gave them (``p K_l(p)``, ``p = K u``)."""
    rim: float
    """m/s: the effective rim speed they reached (the busiest wheel's, for moves of the reference
    length: commanded speed times distance over length)."""
    ratio: float
    """Mean distance achieved over commanded."""
    spread: float
    """Their distances' standard error, as a fraction of the length."""
    runs: int


def anchor_slow_end(
    fit: SurfaceFit, spec: CalibrationSpec, geometry: Geometry, runs: Sequence[RunResult], speed: float
) -> dict[float, SlowAnchor]:
    """Add to each calibrated course's rate curve the point its MOVEs at ``speed`` measured
    (:func:`~omnibot.calibration.experiments.slow_moves`, driven with ``spec`` in the controller).

    At the bottom of the speed range a PWM count is a large share of the speed (2 % at 0.3 m/s on
    the simulated carpet), while the sweep's POWER runs at one level scatter by several % with where
    the wheels stand when each starts: the two levels that bracket the slowest MOVE place its power
    only to a count or two. The MOVEs measure the effective rim speed at exactly the power the
    firmware gives them, averaged over every raw course and where the wheels happen to stand; the
    curve then passes through that point. Courses without measured MOVEs are left as they are."""
    out: dict[float, SlowAnchor] = {}
    table = spec.k_l
    if table is None:
        return out
    for idx, course in enumerate(table.courses_deg):
        if course not in fit.translation:
            continue
        ratios = [
            r.truth.distance / r.commanded
            for r in runs
            if r.folded_deg == course and r.truth is not None and r.truth.distance is not None and r.commanded
        ]
        if not ratios:
            continue
        u = speed * geometry.translation_factor(course)
        p = spec.k * u
        power = p * table.curves[idx](p)
        ratio = statistics.fmean(ratios)
        spread = statistics.stdev(ratios) / math.sqrt(len(ratios)) if len(ratios) > 1 else 0.0
        anchor = SlowAnchor(speed, power, u * ratio, ratio, spread, len(ratios))
        fit.translation[course] = fit.translation[course].with_point(anchor.power, anchor.rim)
        out[course] = anchor
    fit.anchors = out
    return out


def fit_surface(
    surface: str,
    straight: Sequence[RunResult],
    rotation: Sequence[RunResult],
    deadbands: dict[str, int],
    geometry: Geometry,
    *,
    move_length: float,
    rotate_angle: float,
    k: float | None = None,
) -> SurfaceFit:
    """Rate curves of one surface's sweeps; K from the rotation curve (else course 0) unless given."""
    by_course: dict[float, list[RunResult]] = defaultdict(list)
    for r in straight:
        if r.folded_deg is not None:
            by_course[r.folded_deg].append(r)
    if not by_course:
        raise ConfigError(f"{surface}: no straight run was measured; nothing to fit")
    translation: dict[float, RateCurve] = {}
    points: dict[str, list[RatePoint]] = {}
    for course in sorted(by_course):
        runs = by_course[course]
        factors = {r.course_deg or 0.0: geometry.translation_factor(r.course_deg or 0.0) for r in runs}
        pts = rate_points(runs, move_length, factors)
        points[f"course:{course:g}"] = pts
        translation[course] = RateCurve.fit(pts, deadbands.get(f"course:{course:g}"))
    rot_curve = None
    if rotation:
        pts = rate_points(rotation, rotate_angle, geometry.rotation_factor())
        if pts and max(p.rim for p in pts) > 0:
            points["rotation"] = pts
            rot_curve = RateCurve.fit(pts, deadbands.get("rotation"))
    if k is None:
        # the motor's own characteristic: the slope of rotation in place, where every wheel drives and
        # no idle roller drags (the same on any floor for omni wheels); else the first course's
        k = (rot_curve or translation[min(translation)]).slope_k()
    if not (math.isfinite(k) and k > 0):
        raise ConfigError(f"{surface}: the fitted K ({k}) is not positive; the sweep is not usable")
    return SurfaceFit(
        surface,
        round(k, 1),
        tuple(sorted(translation)),
        translation,
        rot_curve,
        points,
        dict(deadbands),
        move_length=move_length,
    )


def build_spec(
    fits: Sequence[SurfaceFit], robot: RobotDescription, geometry: Geometry, kt: PiecewiseLinear | None
) -> CalibrationSpec:
    """The calibration section of one surface, or averaged over several (same calibrated courses)."""
    courses = fits[0].courses
    if any(f.courses != courses for f in fits):
        raise ConfigError(f"surfaces were calibrated on different courses: {[f.courses for f in fits]}")
    k = round(statistics.fmean(f.k for f in fits), 1)
    knots = translation_knots(robot, geometry, k, courses, fits[0].move_length)
    curves = [factor_table([f.translation[c] for f in fits], k, knots) for c in courses]
    k_l = CourseTable(courses_deg=tuple(float(c) for c in courses), curves=tuple(curves))
    rot = [f.rotation for f in fits if f.rotation is not None]
    k_r = factor_table(rot, k, rotation_knots(robot, geometry, k)) if rot else robot_table(robot, "k_r")
    maps = [f.motors for f in fits if f.motors is not None]
    motors = average_motors(maps) if len(maps) == len(fits) and maps else None
    drags = [d for d in (f.roller_spec for f in fits) if d is not None]
    rollers = average_rollers(drags) if drags else None
    return CalibrationSpec(
        k=k,
        k_l=k_l,
        k_t=kt if kt is not None else robot_table(robot, "k_t"),
        k_r=k_r,
        motors=motors,
        rollers=rollers,
        fold_axes_deg=geometry.fold_marker,
    )


def average_rollers(drags: Sequence[RollerDragSpec]) -> RollerDragSpec:
    """The mean roller drag coefficients (the drag is linear in them) and coast tables (a missing
    table counts as no coast)."""
    n = len(drags[0].cos)
    coasts = [d.coast for d in drags if d.coast is not None]
    none = PiecewiseLinear(x=(0.0,), y=(0.0,))
    return RollerDragSpec(
        cos=tuple(round(statistics.fmean(d.cos[i] for d in drags), 2) for i in range(n)),
        sin=tuple(round(statistics.fmean(d.sin[i] for d in drags), 2) for i in range(n)),
        coast=average_tables([d.coast or none for d in drags]) if coasts else None,
    )


def average_motors(maps: Sequence[MotorMapSpec]) -> MotorMapSpec:
    """The mean of motor maps: offsets and speed terms averaged, gain tables averaged on the union of
    their knots."""
    n = len(maps[0].offset)
    speed = None
    if any(m.speed is not None for m in maps):
        speed = tuple(round(statistics.fmean(m.speed_term(i) for m in maps), 1) for i in range(n))
    return MotorMapSpec(
        offset=tuple(round(statistics.fmean(m.offset[i] for m in maps), 1) for i in range(n)),
        gain=tuple(average_tables([m.gain[i] for m in maps]) for i in range(n)),
        speed=speed,
    )


def robot_table(robot: RobotDescription, name: str) -> PiecewiseLinear | None:
    """The robot's current calibration table ``name`` (``kt``, ``kr`` ...), None when it has none."""
    cal = robot.calibration
    table = getattr(cal, name) if cal is not None else None
    return table if isinstance(table, PiecewiseLinear) else None


def average_kt(fits: Sequence[SurfaceFit]) -> PiecewiseLinear | None:
    """The K_t tables of the surfaces averaged, None when no surface has one."""
    tables = [f.kt for f in fits if f.kt is not None]
    return average_tables(tables) if tables else None
