"""The roller drag fit on synthetic runs with known answers (no simulator; the acceptance test
drives the real runs)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from omnibot.calibration.patterns import Geometry
from omnibot.calibration.rollerfit import (
    GROUP,
    RollerFit,
    axis_courses,
    correct_runs,
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
