"""The fits on synthetic data with known answers (pure functions, no simulator)."""

from __future__ import annotations

import pytest

from omnibot.calibration.experiments import SLOW
from omnibot.calibration.fits import (
    FACTOR_MAX,
    SurfaceFit,
    anchor_slow_end,
    average_tables,
    build_spec,
    factor_table,
    fit_kt,
    knot_powers,
)
from omnibot.calibration.patterns import Geometry
from omnibot.calibration.rates import RateCurve, RatePoint
from omnibot.calibration.runs import Motion, RunResult
from omnibot.client import commands
from omnibot.protocol import codes
from omnibot.robot import CalibrationSpec, CourseTable, PiecewiseLinear, RobotDescription
from tests.calibration.test_rates import DEADBAND, SLOPE, linear_rim


def test_factor_table_reproduces_the_needed_power() -> None:
    points = [RatePoint(int(p), 0.0, 0.0, 0.0, linear_rim(p), 4) for p in range(60, 256, 20)]
    curve = RateCurve.fit(points, deadband=int(DEADBAND))
    k = 1.0 / SLOPE
    knots = knot_powers(20, 240, 255)
    table = factor_table([curve], k, knots)
    assert len(table.x) <= codes.CAL_KNOTS_MAX
    assert all(0 < y <= FACTOR_MAX for y in table.y)
    # between knots the firmware interpolates linearly: the power it applies stays within 1 %
    for rim in (0.25, 0.4, 0.7, 1.0):
        p = k * rim
        needed = DEADBAND + rim / SLOPE
        assert p * table(p) == pytest.approx(needed, rel=0.01)


def test_knots_fit_the_protocol() -> None:
    knots = knot_powers(3.2, 400.0, 255)
    assert all(isinstance(k, int) for k in knots)
    assert list(knots) == sorted(set(knots)) and knots[-1] == 255 and knots[0] >= 1
    assert len(knots) <= codes.CAL_KNOTS_MAX


def test_averaging_surfaces_averages_the_needed_power() -> None:
    wood = RateCurve((50.0, 250.0), (0.0, 1.4))
    carpet = RateCurve((70.0, 250.0), (0.0, 1.1))
    k = 150.0
    avg = factor_table([wood, carpet], k, (60, 120, 200))
    for p, y in zip(avg.x, avg.y, strict=True):
        expected = 0.5 * (wood.power_for(p / k) + carpet.power_for(p / k)) / p
        assert y == pytest.approx(expected, abs=1e-3)


def test_fit_kt_divides_by_the_turn_ratio() -> None:
    def turn(p_arg: float, achieved: float, commanded: float) -> RunResult:
        return RunResult(
            kind="turn",
            group="turn",
            command="MOVE",
            duration=1.0,
            truth=Motion(theta=achieved),
            commanded=commanded,
            p_arg=p_arg,
            sign=1,
        )

    current = PiecewiseLinear(x=(0.0, 255.0), y=(1.3, 1.3))
    runs = [turn(20, 1.0, 2.0), turn(20, 1.2, 2.0), turn(60, 2.0, 2.0), turn(90, 0.01, 2.0)]
    kt = fit_kt(runs, current)
    assert kt is not None
    assert kt.x == (20.0, 60.0)  # the run that did not turn is left out
    assert kt.y == pytest.approx((1.3 / 0.55, 1.3), abs=1e-3)
    assert fit_kt([turn(50, 0.0, 2.0)], current) is None


def test_average_tables_on_the_union_of_knots() -> None:
    a = PiecewiseLinear(x=(0.0, 100.0), y=(1.0, 2.0))
    b = PiecewiseLinear(x=(50.0,), y=(3.0,))
    avg = average_tables([a, b])
    assert avg.x == (0.0, 50.0, 100.0)
    assert avg.y == pytest.approx((2.0, 2.25, 2.5))


def test_a_fitted_spec_uploads() -> None:
    curve = RateCurve((50.0, 255.0), (0.0, 1.4))
    table = factor_table([curve], 150.0, knot_powers(10, 250, 255))
    spec = CalibrationSpec(
        k=150.0, k_l=CourseTable(courses_deg=(0.0, 45.0), curves=(table, table)), k_t=table, k_r=table
    )
    cals = commands.calibration(spec)  # raises if anything is outside the protocol's ranges
    assert cals[0].params() == (codes.CAL_K, 0, 0, 1500)
    # K, K_t, K_r, two K_l curves, dropping any curves after them
    assert len(cals) == 1 + 2 * len(table.x) + 2 * (1 + len(table.x)) + 1


def slow_run(folded: float, raw: float, ratio: float) -> RunResult:
    return RunResult(
        kind="straight",
        group=SLOW,
        command="MOVE",
        duration=1.0 / 0.3,
        truth=Motion(x=ratio, y=0.0, theta=0.0, source="test"),
        course_deg=raw,
        folded_deg=folded,
        commanded=1.0,
    )


def test_slow_moves_anchor_the_curve_where_the_tables_put_them(omni4: RobotDescription) -> None:
    """The sweep read the slow end 3 % fast on course 45: MOVEs at the bottom speed through its tables
    fall 3 % short (0.96 and 0.98 of the length), and the curve is made to pass through what they
    reached at the power the tables gave them; the firmware then gives that speed more power. A
    course without MOVEs keeps its curve."""
    geo = Geometry.of(omni4)
    curves = {c: RateCurve((30.0, 60.0, 90.0, 120.0), (0.0, 0.2, 0.4, 0.6)) for c in (0.0, 45.0)}
    fit = SurfaceFit("carpet", 150.0, (0.0, 45.0), dict(curves), None)
    spec = build_spec([fit], omni4, geo, None)
    assert spec.k_l is not None
    runs = [slow_run(45.0, raw, ratio) for raw in (45.0, 135.0) for ratio in (0.96, 0.98)]
    anchors = anchor_slow_end(fit, spec, geo, runs, 0.3)
    assert set(anchors) == {45.0} and fit.anchors == anchors
    a = anchors[45.0]
    u = 0.3 * geo.translation_factor(45.0)
    p = spec.k * u
    assert a.power == pytest.approx(p * spec.k_l.curves[1](p))
    assert a.ratio == pytest.approx(0.97) and a.rim == pytest.approx(0.97 * u) and a.runs == 4
    assert a.spread == pytest.approx(0.01 / 2 * (4 / 3) ** 0.5)  # stdev / sqrt(n)
    assert fit.translation[45.0].rim_at(a.power) == pytest.approx(0.97 * u)
    assert fit.translation[0.0] is curves[0.0]
    after = build_spec([fit], omni4, geo, None)
    assert after.k_l is not None
    assert p * after.k_l.curves[1](p) > a.power + 1.0  # more power for the same speed
    assert after.k_l.curves[0] == spec.k_l.curves[0]
