"""The roller drag fit on synthetic runs with known answers (no simulator; the acceptance test
drives the real runs)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np
import pytest

from omnibot.calibration.patterns import Geometry
from omnibot.calibration.rollerfit import (
    COAST_MAX,
    GROUP,
    CoastMove,
    RollerFit,
    axis_courses,
    correct_runs,
    fit_coast,
    fit_rollers,
    offset_shift,
)
from omnibot.calibration.runs import Motion, RunResult
from omnibot.firmware.power import roller_terms
from omnibot.robot.description import RobotDescription
from tests.calibration.test_fits import run as straight_run

COS = (-5.0, -4.0, -6.0, -3.0)
SIN = (0.5, 1.0, -0.5, 0.0)
SLOPE = 0.007
POWERS = (80, 120, 160)
COAST = {80: 0.0, 120: 0.3, 160: 0.9}


@pytest.fixture(scope="module")
def geo(omni4: RobotDescription) -> Geometry:
    return Geometry.of(omni4)


def drag(geo: Geometry, course: float, counts: tuple[int, ...]) -> float:
    fc, fs = geo.roller_terms(course, counts)
    return sum(COS[i] * fc[i] + SIN[i] * fs[i] for i in geo.idle_wheels(course))


def synthetic_runs(
    geo: Geometry, with_drag: bool = True, noise: float = 0.002, paired: bool = False
) -> list[RunResult]:
    """Runs as roller_runs makes them: three powers, two durations, round the axes, random phases
    (``paired``: wheels 1 and 3 always at the same count, as a mecanum robot's diagonal pair)."""
    rng = np.random.default_rng(1)
    out = []
    for power in POWERS:
        for k in range(4):
            duration = 0.8 * (1 + k % 2)
            for course in axis_courses(geo):
                counts = tuple(int(v) for v in rng.integers(-5000, 5000, size=4))
                if paired:
                    counts = (counts[0], counts[1], counts[0], counts[3])
                rate = SLOPE * (power - 40) + 0.01 * (course // 90)
                d = drag(geo, course, counts) if with_drag else 0.0
                amount = -0.05 + duration * rate - SLOPE * (duration + COAST[power]) * d
                amount += float(rng.normal(0.0, noise))
                out.append(replace(straight_run(power, duration, amount, course), group=GROUP, counts=counts))
    return out


def test_geometry_matches_the_firmware(geo: Geometry) -> None:
    assert axis_courses(geo) == [0.0, 90.0, 180.0, 270.0]
    assert geo.idle_wheels(0.0) == [0, 2] and geo.idle_wheels(90.0) == [1, 3] and geo.idle_wheels(45.0) == []
    assert geo.roller_pitch == (55.0,) * 4  # 440 counts per turn, 8 rollers
    counts = [12, 40, -3, 27]
    fc, fs = geo.roller_terms(0.0, counts)
    ref_c, ref_s = [0.0] * 4, [0.0] * 4
    roller_terms([list(d) for d in geo.roller_dir], list(geo.roller_pitch), counts, 1.0, 0.0, ref_c, ref_s)
    assert (fc, fs) == (ref_c, ref_s)
    assert fc[0] == pytest.approx(math.cos(2 * math.pi * 12 / 55)) and fc[1] == 0.0  # wheel 2 rolls along


def test_fit_recovers_the_drag_and_the_coast(geo: Geometry) -> None:
    fit = fit_rollers(geo, synthetic_runs(geo))
    assert fit is not None and fit.kept and fit.runs == 48
    assert fit.cos == pytest.approx(COS, abs=0.3) and fit.sin == pytest.approx(SIN, abs=0.3)
    assert fit.slope == pytest.approx(SLOPE, rel=0.02)
    assert fit.coast == pytest.approx([COAST[p] for p in POWERS], abs=0.1)
    assert fit.rms_after < 0.003 < fit.rms_before
    table = fit.coast_table
    assert table.x[0] == 0.0 and table.y[0] == 0.0 and list(table.x) == sorted(table.x)
    spec = fit.spec
    assert spec.cos == fit.cos and spec.coast == table


def test_wheels_that_always_turn_together_share_their_drag(geo: Geometry) -> None:
    fit = fit_rollers(geo, synthetic_runs(geo, paired=True))
    assert fit is not None and fit.kept
    half = (COS[0] + COS[2]) / 2, (SIN[0] + SIN[2]) / 2
    assert (fit.cos[0], fit.sin[0]) == pytest.approx(half, abs=0.3)
    assert (fit.cos[2], fit.sin[2]) == pytest.approx(half, abs=0.3)
    assert fit.cos[1] == pytest.approx(COS[1], abs=0.3)


def test_no_drag_is_not_kept(geo: Geometry) -> None:
    fit = fit_rollers(geo, synthetic_runs(geo, with_drag=False))
    assert fit is not None and not fit.kept
    assert fit.spec.cos == (0.0,) * 4 and fit.spec.coast is None
    assert fit.drag(geo, 0.0, (10, 20, 30, 40)) == 0.0


def test_runs_that_cannot_tell_give_none(geo: Geometry) -> None:
    runs = synthetic_runs(geo)
    assert fit_rollers(geo, [r for r in runs if r.power == POWERS[0]]) is None  # one power
    assert fit_rollers(geo, [RunResult(**{**r.__dict__, "counts": None}) for r in runs]) is None
    assert fit_rollers(geo, []) is None


def test_correct_runs_puts_the_mean_drag_back_on_axis_runs_only(geo: Geometry) -> None:
    fit = RollerFit(
        cos=COS,
        sin=SIN,
        slope=SLOPE,
        speeds=(0.5,),
        coast=(0.2,),
        runs=48,
        rms_before=0.05,
        rms_after=0.002,
        kept=True,
    )
    counts = (30, 0, 17, 0)
    axis = RunResult(
        kind="straight",
        group="course:0",
        command="POWER",
        duration=1.0,
        truth=Motion(x=0.5, y=0.0, theta=0.0),
        course_deg=180.0,
        folded_deg=0.0,
        counts=counts,
    )
    off_axis = RunResult(**{**axis.__dict__, "course_deg": 45.0, "folded_deg": 45.0})
    fixed, same = correct_runs(geo, fit, [axis, off_axis])
    expected = SLOPE * (1.0 + fit.coast_table(0.5)) * drag(geo, 180.0, counts)
    assert fixed.correction == pytest.approx(expected) and fixed.amount == pytest.approx(0.5 + expected)
    assert same is off_axis and same.correction == 0.0


def test_offset_shift_evens_out_the_axis_courses(geo: Geometry) -> None:
    # MOVEs on courses 0 and 180 (motors 2 and 4 drive) run half a count ahead, 90 and 270 behind
    ahead = [(c, 0.5 if c % 180 == 0 else -0.5, 0.01) for c in (0.0, 90.0, 180.0, 270.0)] * 3
    shift = offset_shift(geo, ahead)
    assert sum(shift) == pytest.approx(0.0, abs=0.05)
    assert shift == pytest.approx([0.5, -0.5, 0.5, -0.5], abs=0.05)
    assert offset_shift(geo, []) == [0.0] * 4
    # offsets act on |power|: courses 45 and 135 drive all four motors alike and cannot be told apart
    assert offset_shift(geo, [(45.0, 1.0, 0.01), (135.0, -1.0, 0.01)]) == [0.0] * 4
    # course 15 leans on motors 2 and 4, course 105 on 1 and 3
    shift = offset_shift(geo, [(15.0, 1.0, 0.01), (105.0, -1.0, 0.01)])
    assert shift[1] == shift[3] < 0.0 < shift[0] == shift[2]
    # a fast MOVE's counts (small mu) weigh less than a slow one's
    slow_fast = [(0.0, 1.0, 0.02), (90.0, -1.0, 0.02), (0.0, -4.0, 0.002), (90.0, 4.0, 0.002)]
    assert offset_shift(geo, slow_fast)[1] < 0.0


SPEEDS = (0.3, 0.38, 0.45, 0.53)
LENGTH = 1.0


def true_coast(speed: float) -> float:
    """s: the coast line the synthetic MOVEs follow (as the default run's carpet: negative when slow)."""
    return -1.2 + 4.0 * (speed - 0.3)


def coast_moves(
    noise: float, seed: int = 7, skip: float | None = None, coast: Callable[[float], float] = true_coast
) -> list[CoastMove]:
    """MOVEs as tune_coast makes them (the slowest speed twice as often, term on every other round,
    gain from a drag run's guess), with ``distance = e + mu (g - G(V)) D`` plus ``noise`` m."""
    rng = np.random.default_rng(seed)
    out = []
    for speed in SPEEDS:
        need = 1.0 + coast(speed) * speed / LENGTH
        guess = 1.0 + 0.3 * speed / LENGTH
        mu = 0.03 - 0.08 * (speed - 0.3)
        for k in range(8 if speed == SPEEDS[0] else 4):
            for course in (0.0, 90.0, 180.0, 270.0):
                d = float(rng.uniform(-6.0, 6.0))
                g = guess if k % 2 == 0 else 0.0
                e = 0.97 + 0.004 * (course // 90)
                distance = e + mu * (g - need) * d + float(rng.normal(0.0, noise))
                if speed != skip:
                    out.append(CoastMove(speed, course, d, g, distance))
    return out


def coast_of(found: list[tuple[float, float, float, float]]) -> list[float]:
    return [(gain - 1.0) * LENGTH / speed for speed, _, _, gain in found]


def test_coast_line_recovers_the_coast_at_every_speed() -> None:
    got = fit_coast(SPEEDS, coast_moves(noise=0.0), LENGTH)
    assert got is not None
    found, ahead = got
    assert [f[0] for f in found] == list(SPEEDS)
    assert coast_of(found) == pytest.approx([true_coast(v) for v in SPEEDS], abs=0.01)
    assert found[0][2] == pytest.approx(0.03, rel=0.01)  # mu at 0.3 m/s
    assert found[0][1] == pytest.approx(found[0][2] * found[0][3])  # lambda = mu G
    # course 270 runs 6 mm ahead of the mean of the courses, in PWM counts of mu
    lead = {c: n for c, n, mu in ahead if mu == pytest.approx(found[0][2])}
    assert lead[270.0] == pytest.approx(0.006 / 0.03, rel=0.02)


def test_coast_line_holds_under_scatter_where_one_number_per_speed_does_not() -> None:
    # 2 cm of scatter: each speed's own lambda / mu (the per-speed fit before 2026-12-02) puts the
    # coast at 0.53 m/s at -1.31 s, 1 s off, and at 3 cm cannot tell 0.53 m/s at all (which lost
    # the whole table); the line fitted over all 80 MOVEs stays within 0.4 s at every speed
    got = fit_coast(SPEEDS, coast_moves(noise=0.02, seed=9), LENGTH)
    assert got is not None
    assert coast_of(got[0]) == pytest.approx([true_coast(v) for v in SPEEDS], abs=0.4)
    got = fit_coast(SPEEDS, coast_moves(noise=0.03, seed=9), LENGTH)
    assert got is not None and len(got[0]) == len(SPEEDS)


def test_a_speed_without_moves_still_gets_its_point_on_the_line() -> None:
    got = fit_coast(SPEEDS, coast_moves(noise=0.001, skip=0.45), LENGTH)
    assert got is not None
    found, ahead = got
    assert coast_of(found)[2] == pytest.approx(true_coast(0.45), abs=0.1)
    assert found[2][1:3] == (0.0, 0.0) and all(mu != 0.0 for _, _, mu in ahead)
    assert len(ahead) == 12  # three speeds' four courses


def test_coast_line_stays_within_its_bounds_and_says_when_it_cannot_tell() -> None:
    # MOVEs that want a longer coast than any drag run's get the bound, not an extrapolation
    got = fit_coast(SPEEDS, coast_moves(0.0, coast=lambda v: 5.0), LENGTH)
    assert got is not None
    assert coast_of(got[0]) == pytest.approx([COAST_MAX] * len(SPEEDS))
    # and a gain that would drive against the travel is never fitted
    got = fit_coast(SPEEDS, coast_moves(0.0, coast=lambda v: -5.0), LENGTH)
    assert got is not None and all(gain >= 0.0 for *_, gain in got[0])
    assert fit_coast(SPEEDS, [m for m in coast_moves(0.0) if m.speed == 0.3], LENGTH) is None  # one speed
    assert fit_coast(SPEEDS, [], LENGTH) is None
    off = [replace(m, gain=0.0) for m in coast_moves(0.0)]  # the term never on: nothing to tell
    assert fit_coast(SPEEDS, off, LENGTH) is None
