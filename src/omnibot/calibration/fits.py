"""Fits of seed 000's calibration functions from measured runs (pure functions, no I/O).

The firmware turns a requested motion into power as ``P = K * f(p) * rim speed`` where ``p = K *
(busiest wheel's rim speed)`` is the uncalibrated power and ``f`` is K_l(p, course) for translation,
K_r(p) for rotation in place and K_t(p) for the turning of a curved MOVE (docs/firmware.md). So
``f(p)`` must be the power that really gives the rim speed ``p / K``, divided by ``p``.

From the runs of one power level (each at two or more durations) the steady rate and the start/stop
loss separate: ``amount(T) = rate * T + loss``; the loss is then smoothed over the levels as
``-(a rate + b rate^2)`` (:func:`loss_model`) and each level's rate refitted with it. A MOVE of length ``L`` at speed V lasts L / V, so
it lands on L when ``rate * L / V + loss = L``: the *effective* rate for moves of the reference
length is ``rate / (1 - loss / L)`` (the same for ROTATE and its reference angle). Times the
busiest wheel's rim factor this is a rim speed; :class:`RateCurve` holds rim speed against power,
made monotone (pool-adjacent-violators) and anchored at the dead band, and inverts it. The factor
tables sample ``power_for(p / K) / p`` at integer knots spaced geometrically over the powers the
robot's speed range needs (the factor is close to ``a / p + b``, so knots dense at low power keep
the linear interpolation within a fraction of a percent). Averaging over surfaces averages the
power needed for the same uncalibrated power, as seed 000 averaged wood and carpet.

K_t is fitted from curved MOVEs instead: the body's turn against the commanded one gives the ratio
by which the factor in use was off, ``K_t,new(p) = K_t,old(p) / ratio`` (run twice, it converges).
"""

from __future__ import annotations

import math
import statistics
from collections import defaultdict
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

from omnibot.calibration.coastfit import CoastTuning
from omnibot.calibration.motorfit import Balance
from omnibot.calibration.patterns import Geometry
from omnibot.calibration.plan import speed_range
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
LOSS_LIMIT = 0.5
"""The start/stop loss (or a coasting gain) is never taken as more than this fraction of the
reference amount."""


@dataclass(frozen=True)
class RatePoint:
    """One power level of a sweep: steady rate, start/stop loss and the effective rim speed."""

    power: int
    rate: float
    """Steady rate: m/s (straight) or rad/s (rotation)."""
    loss: float
    """Amount (m or rad) at zero duration: what starting and stopping add (negative: lose)."""
    effective: float
    """Rate that makes a motion of the reference amount land on it."""
    rim: float
    """Effective rim speed of the busiest wheel, m/s."""
    runs: int


def loss_model(levels: Sequence[tuple[float, float]]) -> tuple[float, float]:
    """(a, b) of ``loss(rate) = -(a rate + b rate^2)`` fitted to per-level (rate, loss) pairs.

    Starting lags behind the power (a time constant: ``a``) and, where the motors' current limit
    caps the acceleration, by the square of the speed (``b``); coasting gives some back (a heavy
    robot that coasts far has a negative loss: a gain). One smooth model across all levels is far
    less noisy than each level's own two-point intercept (on a floor where the rollers' resistance
    varies from run to run that intercept scatters widely). With fewer than three levels one term.
    """
    pts = [(r, -loss) for r, loss in levels if r > 0]
    if not pts:
        return 0.0, 0.0
    s11 = sum(r * r for r, _ in pts)
    s12 = sum(r**3 for r, _ in pts)
    s22 = sum(r**4 for r, _ in pts)
    y1 = sum(r * g for r, g in pts)
    y2 = sum(r * r * g for r, g in pts)
    det = s11 * s22 - s12 * s12
    if len(pts) >= 3 and det > 1e-12:
        return (y1 * s22 - y2 * s12) / det, (s11 * y2 - s12 * y1) / det
    candidates = [(y1 / s11, 0.0), (0.0, y2 / s22)]  # one term only
    return min(candidates, key=lambda ab: sum((g - ab[0] * r - ab[1] * r * r) ** 2 for r, g in pts))


def rate_points(
    runs: Iterable[RunResult], reference: float, factor: dict[float, float] | float
) -> list[RatePoint]:
    """Per power level, the rates of runs measured by the truth (see the module docstring).

    Each level's two durations give a first (rate, loss); the losses are then smoothed by
    :func:`loss_model` across the levels and each level's rate refitted with its loss from the model.
    ``factor``: rim speed of the busiest wheel per unit rate, one number or per raw course (deg).
    """
    by_power: dict[int, list[RunResult]] = defaultdict(list)
    for r in runs:
        if r.power is not None and r.amount is not None:
            by_power[r.power].append(r)
    levels: list[tuple[int, list[float], list[float], float]] = []  # power, durations, mean amounts, m
    raw: list[tuple[float, float]] = []
    for power in sorted(by_power):
        group = by_power[power]
        by_t: dict[float, list[float]] = defaultdict(list)
        for r in group:
            assert r.amount is not None
            by_t[r.duration].append(r.amount)
        ts = sorted(by_t)
        means = [statistics.fmean(by_t[t]) for t in ts]
        if isinstance(factor, dict):
            m = statistics.fmean(factor[r.course_deg or 0.0] for r in group)
        else:
            m = factor
        levels.append((power, ts, means, m))
        if len(ts) >= 2:
            t_mean, a_mean = statistics.fmean(ts), statistics.fmean(means)
            sxx = sum((t - t_mean) ** 2 for t in ts)
            rate = sum((t - t_mean) * (a - a_mean) for t, a in zip(ts, means, strict=True)) / sxx
            raw.append((rate, a_mean - rate * t_mean))
    a, b = loss_model(raw)
    limit = LOSS_LIMIT * reference
    out = []
    for power, ts, means, m in levels:

        def misfit(rate: float, ts: list[float] = ts, means: list[float] = means) -> float:
            loss = min(max(-(a * rate + b * rate * rate), -limit), limit)
            return sum((x - rate * t - loss) ** 2 for t, x in zip(ts, means, strict=True))

        # amount = rate T - (a rate + b rate^2): least squares in rate
        rate = golden_min(misfit, 0.0, 3.0 * max(max(means) / min(ts), 1e-6))
        loss = min(max(-(a * rate + b * rate * rate), -limit), limit)
        effective = rate / (1.0 - loss / reference) if rate > 0 else 0.0
        out.append(RatePoint(power, rate, loss, effective, effective * m, len(by_power[power])))
    return out


def golden_min(f: Callable[[float], float], lo: float, hi: float, iterations: int = 60) -> float:
    """The minimum of a unimodal ``f`` on [lo, hi] by golden-section search."""
    g = (math.sqrt(5.0) - 1.0) / 2.0
    x1, x2 = hi - g * (hi - lo), lo + g * (hi - lo)
    f1, f2 = f(x1), f(x2)
    for _ in range(iterations):
        if f1 <= f2:
            hi, x2, f2 = x2, x1, f1
            x1 = hi - g * (hi - lo)
            f1 = f(x1)
        else:
            lo, x1, f1 = x1, x2, f2
            x2 = lo + g * (hi - lo)
            f2 = f(x2)
    return 0.5 * (lo + hi)


def isotonic(values: Sequence[float]) -> list[float]:
    """The non-decreasing sequence closest to ``values`` in least squares (pool adjacent violators)."""
    blocks: list[list[float]] = []  # [sum, count]
    for v in values:
        blocks.append([v, 1.0])
        while len(blocks) > 1 and blocks[-2][0] / blocks[-2][1] > blocks[-1][0] / blocks[-1][1]:
            s, n = blocks.pop()
            blocks[-1][0] += s
            blocks[-1][1] += n
    out: list[float] = []
    for s, n in blocks:
        out += [s / n] * int(n)
    return out


@dataclass(frozen=True)
class RateCurve:
    """Rim speed of the busiest wheel (m/s) against power: monotone, zero up to the dead band.

    Between the measured levels the curve is a monotone cubic (Fritsch-Carlson), so its bend near
    the dead band and where acceleration limits the speed is followed; beyond the last level it is
    extended linearly.
    """

    powers: tuple[float, ...]
    rims: tuple[float, ...]

    @classmethod
    def fit(cls, points: Sequence[RatePoint], deadband: int | None = None) -> RateCurve:
        """The curve through the measured ``points`` (made monotone), zero up to ``deadband``;
        ConfigError when no run moved the robot."""
        pts = sorted((p.power, p.rim) for p in points)
        if not pts or max(r for _, r in pts) <= 0.0:
            raise ConfigError(
                "no run moved the robot: nothing to fit (is the robot on the floor and powered?)"
            )
        powers = [float(p) for p, _ in pts]
        rims = isotonic([max(r, 0.0) for _, r in pts])
        _start(powers, rims, deadband)
        return cls(tuple(powers), tuple(rims))

    @property
    def deadband(self) -> float:
        """Highest power at which the curve is still zero."""
        last = self.powers[0]
        for p, r in zip(self.powers, self.rims, strict=True):
            if r > 0.0:
                break
            last = p
        return last

    @cached_property
    def _slopes(self) -> list[float]:
        """Fritsch-Carlson tangents at the points (monotone cubic Hermite)."""
        ps, rs = self.powers, self.rims
        n = len(ps)
        if n < 2:
            return [0.0] * n
        d = [(rs[i + 1] - rs[i]) / (ps[i + 1] - ps[i]) for i in range(n - 1)]
        m = (
            [d[0]]
            + [0.0 if d[i - 1] * d[i] <= 0 else 0.5 * (d[i - 1] + d[i]) for i in range(1, n - 1)]
            + [d[-1]]
        )
        if n > 2 and ps[0] == 0.0 and ps[1] == 1.0 and rs[0] == 0.0 < rs[1]:
            m[1] = d[1]  # the first count's jump (:func:`_start`): the line of the levels goes on from it
        for i in range(n - 1):
            if d[i] == 0.0:
                m[i] = m[i + 1] = 0.0
                continue
            a, b = m[i] / d[i], m[i + 1] / d[i]
            h = a * a + b * b
            if h > 9.0:
                t = 3.0 / math.sqrt(h)
                m[i], m[i + 1] = t * a * d[i], t * b * d[i]
        return m

    def rim_at(self, power: float) -> float:
        """Rim speed at ``power`` PWM counts, m/s (held below the first level, linear beyond the last)."""
        ps, rs, m = self.powers, self.rims, self._slopes
        if power <= ps[0]:
            return rs[0]
        if power >= ps[-1]:
            return rs[-1] + self._top_slope() * (power - ps[-1])
        i = next(k for k in range(1, len(ps)) if power <= ps[k])
        h = ps[i] - ps[i - 1]
        t = (power - ps[i - 1]) / h
        h00, h10 = 2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t
        h01, h11 = -2 * t**3 + 3 * t**2, t**3 - t**2
        return h00 * rs[i - 1] + h10 * h * m[i - 1] + h01 * rs[i] + h11 * h * m[i]

    def power_for(self, rim: float) -> float:
        """The lowest power that gives ``rim`` m/s (linear beyond the last point)."""
        ps, rs = self.powers, self.rims
        if rim <= 0.0:
            return self.deadband
        if rim >= rs[-1]:
            return ps[-1] + (rim - rs[-1]) / self._top_slope()
        i = next(k for k in range(1, len(ps)) if rim <= rs[k] and rs[k] > rs[k - 1])
        lo, hi = ps[i - 1], ps[i]
        for _ in range(50):  # bisection on the monotone cubic
            mid = 0.5 * (lo + hi)
            if self.rim_at(mid) < rim:
                lo = mid
            else:
                hi = mid
        return 0.5 * (lo + hi)

    def _top_slope(self) -> float:
        """rim per power for extrapolation: the chord over the upper half of the curve (robust to a
        flat or noisy last level)."""
        ps, rs = self.powers, self.rims
        top = rs[-1]
        if top <= 0.0:
            return 1e-3
        j = next(i for i, r in enumerate(rs) if r >= 0.5 * top)
        if j == len(ps) - 1:
            j = max(0, j - 1)
        slope = (top - rs[j]) / (ps[-1] - ps[j]) if ps[-1] > ps[j] else 0.0
        return max(slope, 1e-4)

    def with_point(self, power: float, rim: float) -> RateCurve:
        """The curve with (``power``, ``rim``) measured as well: the point added (replacing a level
        at the same power) and the curve made monotone again."""
        deadband = self.deadband
        pts = sorted(
            [(p, r) for p, r in zip(self.powers, self.rims, strict=True) if p != power and p > 1.0]
            + [(power, rim)]
        )  # the start (at most the first count, :func:`_start`) drawn again through the new point
        powers = [p for p, _ in pts]
        rims = isotonic([r for _, r in pts])
        _start(powers, rims, deadband)
        return RateCurve(tuple(powers), tuple(rims))

    def slope_k(self) -> float:
        """PWM counts per m/s of rim speed over the upper half of the curve: the motor's K."""
        pairs = [(p, r) for p, r in zip(self.powers, self.rims, strict=True) if r >= 0.3 * self.rims[-1]]
        if len(pairs) < 2:
            pairs = list(zip(self.powers, self.rims, strict=True))[-2:]
        pm = statistics.fmean(p for p, _ in pairs)
        rm = statistics.fmean(r for _, r in pairs)
        srr = sum((r - rm) ** 2 for _, r in pairs)
        if srr <= 0.0:
            return self.powers[-1] / max(self.rims[-1], 1e-6)
        return sum((p - pm) * (r - rm) for p, r in pairs) / srr

    def as_dict(self) -> dict[str, Any]:
        """The measured levels as plain data."""
        return {"powers": list(self.powers), "rims": list(self.rims)}


def _start(powers: list[float], rims: list[float], deadband: float | None) -> None:
    """Where the curve through the levels ``powers``, ``rims`` (sorted, made monotone) starts: the
    points below its first level inserted in place.

    The dead band is where a short run from rest turns the robot visibly. Where the line through the
    first two levels reaches zero lower (through a motor map, whose offsets already make up the
    friction, the robot runs steadily at no power above them), the curve starts there: anchored at
    the dead band its first segment would be steeper than the levels above and the cubic would bulge
    over them, under-powering slow ROTATEs. Where that line reaches zero below the first count, the
    first count already carries the robot at the line's speed there (the firmware ramps a motor's
    offset in over its first count, so the power jumps from 0 to the offset and one count): the curve
    jumps from (0, 0) to that point, where it went to (0, 0) in a line before and so gave slow MOVEs
    too much power (mecanum4 forward on carpet at 0.1 m/s: +12 %, its first count 0.078 m/s)."""
    if not powers or rims[0] <= 0.0:
        return
    slope = next(
        ((rims[i] - rims[0]) / (powers[i] - powers[0]) for i in range(1, len(powers)) if rims[i] > rims[0]),
        None,
    )
    zero = powers[0] - rims[0] / slope if slope is not None else powers[0] - 1.0
    if slope is not None and zero < 1.0 < powers[0] and (deadband is None or deadband < powers[0]):
        first = rims[0] - slope * (powers[0] - 1.0)
        powers[:0] = [0.0, 1.0]
        rims[:0] = [0.0, first]
        return
    if deadband is not None and deadband < powers[0]:
        zero = min(float(deadband), zero)
    powers.insert(0, max(0.0, zero))
    rims.insert(0, 0.0)


# --------------------------------------------------------------------------- factor tables


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
