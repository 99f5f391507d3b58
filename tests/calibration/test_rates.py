"""A sweep's rates: rate and loss of a power level, the monotone rim-speed curve and its inverse."""

from __future__ import annotations

import itertools

import pytest

from omnibot.calibration.rates import RateCurve, RatePoint, isotonic, rate_points
from omnibot.calibration.runs import Motion, RunResult

DEADBAND = 50.0
SLOPE = 0.007  # m/s of rim speed per PWM count above the dead band


def linear_rim(power: float) -> float:
    return max(0.0, SLOPE * (power - DEADBAND))


def run(power: int, duration: float, amount: float, course: float = 0.0) -> RunResult:
    return RunResult(
        kind="straight",
        group="course:0",
        command="POWER",
        duration=duration,
        truth=Motion(x=amount, y=0.0, theta=0.0, source="test"),
        power=power,
        course_deg=course,
        folded_deg=0.0,
    )


def test_isotonic() -> None:
    assert isotonic([1.0, 3.0, 2.0, 4.0]) == [1.0, 2.5, 2.5, 4.0]
    assert isotonic([3.0, 2.0, 1.0]) == [2.0, 2.0, 2.0]
    assert isotonic([0.0, 1.0, 2.0]) == [0.0, 1.0, 2.0]


def test_rate_and_loss_from_two_durations() -> None:
    # amount = rate * T + loss with rate 0.5 m/s, loss -0.05 m: a 1 m move lands when V = 0.5 / 1.05
    runs = [run(100, t, 0.5 * t - 0.05) for t in (1.0, 2.5)]
    (p,) = rate_points(runs, reference=1.0, factor=1.0)
    assert p.rate == pytest.approx(0.5)
    assert p.loss == pytest.approx(-0.05)
    assert p.effective == pytest.approx(0.5 / 1.05)
    # a move of the reference length at the effective speed covers it: rate * (L / V) + loss = L
    assert p.rate * (1.0 / p.effective) + p.loss == pytest.approx(1.0)


def test_rate_curve_is_monotone_and_inverts() -> None:
    points = [
        RatePoint(int(p), 0.0, 0.0, 0.0, linear_rim(p) * (1.08 if p == 120 else 1.0), 4)
        for p in (60, 80, 100, 120, 140, 180, 220)
    ]  # one noisy level above its neighbour
    curve = RateCurve.fit(points, deadband=int(DEADBAND))
    assert curve.powers[0] == DEADBAND and curve.rims[0] == 0.0
    assert list(curve.rims) == sorted(curve.rims)
    xs = [DEADBAND + k for k in range(0, 200, 3)]
    ys = [curve.rim_at(x) for x in xs]
    assert all(b >= a - 1e-12 for a, b in itertools.pairwise(ys))
    for rim in (0.05, 0.3, 0.6, 1.2, 1.6):  # 1.6 m/s is beyond the last level: extrapolated
        assert curve.rim_at(curve.power_for(rim)) == pytest.approx(rim, abs=1e-6)
    assert curve.power_for(0.0) == DEADBAND


def test_a_curve_that_runs_below_its_dead_band_starts_where_its_levels_say() -> None:
    """Rotation through a motor map (the default omni4 run): the offsets make up the friction, so the
    rim speed is 0.0168 + 0.00713 p m/s from p = 0 (the simulator's, steady), but the dead band search
    finds 2 counts. Anchored there the cubic bulged over the levels above and gave a ROTATE at 90
    deg/s (rim 0.151 m/s) 0.58 counts too few (the default run: 61 counts where it needs 62, -5.2 %);
    started where the levels' line reaches zero (clipped at no power) it is within 0.25 counts."""

    def rotation(p: float) -> float:
        return 0.0168 + 0.00713 * p

    levels = (11, 28, 50, 77)
    curve = RateCurve.fit([RatePoint(p, 0.0, 0.0, 0.0, rotation(p), 4) for p in levels], deadband=2)
    assert curve.powers[:2] == (0.0, 1.0) and curve.rims[0] == 0.0  # the line's crossing (-2.4) is
    assert curve.rims[1] == pytest.approx(rotation(1.0))  # below the first count: it carries the robot
    at_dead_band = RateCurve((2.0, *levels), (0.0, *(rotation(p) for p in levels)))
    for rim in (0.12, 0.151, 0.2, 0.3, 0.45):
        needed = (rim - 0.0168) / 0.00713
        assert curve.power_for(rim) == pytest.approx(needed, abs=0.25)
        assert abs(curve.power_for(rim) - needed) <= 0.5 * abs(at_dead_band.power_for(rim) - needed) + 1e-6
    # a curve that starts convex (friction, roller drag) keeps its dead band
    convex = [RatePoint(int(p), 0.0, 0.0, 0.0, linear_rim(p), 4) for p in (60, 80, 100)]
    assert RateCurve.fit(convex, deadband=int(DEADBAND)).powers[0] == DEADBAND
    late = [RatePoint(p, 0.0, 0.0, 0.0, SLOPE * (p - 60.0), 4) for p in (70, 90, 110)]
    assert RateCurve.fit(late, deadband=int(DEADBAND)).powers[0] == DEADBAND


def test_a_slow_anchor_below_the_levels_keeps_the_first_counts_speed() -> None:
    """mecanum4 forward on the simulated carpet: through the motor map's offsets (47 counts) the first
    nominal count already carries the robot at 0.078 m/s (rim 0.0696 + 0.0088 p). The slow end's MOVEs
    at 0.1 m/s, given 6.29 counts, went 0.125 m/s; the curve through them and (0, 0) asked 4.8 counts
    for 0.1 m/s (+12 %, the check's +11.5 %). From the first count it asks the 3.5 it needs."""

    def forward(p: float) -> float:
        return 0.0696 + 0.0088 * p

    levels = (11, 28, 49, 75)
    curve = RateCurve.fit([RatePoint(p, 0.0, 0.0, 0.0, forward(p), 4) for p in levels], deadband=2)
    anchored = curve.with_point(6.29, forward(6.29))
    assert anchored.powers[:3] == (0.0, 1.0, 6.29) and anchored.rims[1] == pytest.approx(forward(1.0))
    for rim in (0.1, 0.12, 0.15, 0.3):
        assert anchored.power_for(rim) == pytest.approx((rim - 0.0696) / 0.0088, abs=0.25), rim
    through_zero = RateCurve((0.0, 6.29, *levels), (0.0, *(forward(p) for p in (6.29, *levels))))
    assert through_zero.power_for(0.1) > 1.3 * anchored.power_for(0.1)  # what it asked before: too much
    late = RateCurve.fit([RatePoint(p, 0.0, 0.0, 0.0, 0.01 * (p - 20), 4) for p in (30, 50)], deadband=22)
    assert late.with_point(25.0, 0.05).powers[:2] == (20.0, 25.0)  # a start above the first count stays


def test_a_point_joins_the_curve_monotone() -> None:
    curve = RateCurve((50.0, 60.0, 80.0, 100.0), (0.0, 0.07, 0.21, 0.35))
    moved = curve.with_point(70.0, 0.13)
    assert moved.powers == (50.0, 60.0, 70.0, 80.0, 100.0)
    assert moved.rim_at(70.0) == pytest.approx(0.13)
    assert moved.power_for(0.13) == pytest.approx(70.0)
    # a level at the same power is replaced; a point out of order is pooled with its neighbour
    assert curve.with_point(80.0, 0.2).rims == (0.0, 0.07, 0.2, 0.35)
    assert curve.with_point(90.0, 0.19).rims == pytest.approx((0.0, 0.07, 0.2, 0.2, 0.35))
