"""The roller drag fit on synthetic runs with known answers, and its MOVEs at chosen idle phases on the
simulated nominal omni4 on carpet (lockstep; the acceptance test drives the whole calibration)."""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from omnibot.calibration.calfile import load_calibration
from omnibot.calibration.coastfit import fit_idle_drag, idle_row, spec_drag
from omnibot.calibration.patterns import Geometry
from omnibot.calibration.rollerfit import (
    GROUP,
    RollerFit,
    axis_courses,
    correct_runs,
    fit_rollers,
    offset_shift,
)
from omnibot.calibration.rollers import probe_drag, set_idle_phase, tune_coast
from omnibot.calibration.runner import Runner
from omnibot.calibration.runs import Motion, RunResult
from omnibot.calibration.tap import TelemetryTap
from omnibot.calibration.truth import SimTruth
from omnibot.firmware.power import roller_terms
from omnibot.robot import CalibrationSpec, PiecewiseLinear, RobotDescription, RollerDragSpec
from tests.calibration.conftest import sim_client
from tests.calibration.test_rates import run as straight_run

DATA = Path(__file__).resolve().parents[1] / "data"

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


def synthetic_moves(
    geo: Geometry, uploaded: RollerDragSpec, gain: float = 1.0, noise: float = 0.002, rounds: int = 8
) -> tuple[list[list[float]], list[float]]:
    """MOVE rows as tune_coast makes them at one speed: round the axes, the term of ``uploaded`` on in
    every other round, random phases; the true drag is COS/SIN and a count is worth MU of distance."""
    rng = np.random.default_rng(2)
    courses = axis_courses(geo)
    rows, b = [], []
    for k in range(rounds):
        for course in courses:
            counts = tuple(int(v) for v in rng.integers(-5000, 5000, size=4))
            term = gain * spec_drag(geo, uploaded, course, counts) if k % 2 == 0 else 0.0
            distance = 0.98 + 0.01 * (course // 90) + MU * (term - drag(geo, course, counts))
            rows.append(idle_row(geo, courses, course, counts, term))
            b.append(distance + float(rng.normal(0.0, noise)))
    return rows, b


MU = 0.023
"""m of a 1 m MOVE per PWM count (carpet at 0.3 m/s)."""


def test_moves_measure_each_idle_wheels_drag(geo: Geometry) -> None:
    # the term uploaded is the drag runs' estimate: the wrong size and phase (as on the nominal omni4)
    wrong = RollerDragSpec(cos=(-0.8, -3.0, -1.0, -3.1), sin=(-0.8, -1.9, -1.4, -2.1))
    rows, b = synthetic_moves(geo, wrong, gain=0.65)
    got = fit_idle_drag(geo, axis_courses(geo), rows, b)
    assert got is not None
    assert got.cos == pytest.approx(COS, abs=0.4) and got.sin == pytest.approx(SIN, abs=0.4)
    assert got.power == pytest.approx(MU, rel=0.05)
    # courses 90 and 270 ran 1 cm ahead of 0 and 180 (about 0.43 counts at MU)
    lead = {c: counts for c, counts, _ in got.ahead}
    assert lead[90.0] - lead[0.0] == pytest.approx(0.01 / MU, abs=0.15)
    # without the term nothing tells what a count is worth: no answer rather than a guess
    off_rows = [[*r[:-1], 0.0] for r in rows]
    assert fit_idle_drag(geo, axis_courses(geo), off_rows, b) is None
    assert fit_idle_drag(geo, axis_courses(geo), [], []) is None
    assert fit_idle_drag(geo, axis_courses(geo), rows[:10], b[:10]) is None  # too few MOVEs


@contextmanager
def carpet_runner(robot: RobotDescription) -> Iterator[Runner]:
    """A runner on the simulated nominal omni4 on carpet (lockstep, seed 1), truth from the simulator."""
    with sim_client(robot, "carpet", seed=1) as client:
        tap = TelemetryTap(client, robot)
        tap.start()
        runner = Runner(client, robot, SimTruth(client.link.device.sim), tap)  # type: ignore[attr-defined]
        try:
            yield runner
        finally:
            runner.close()
            tap.stop()


def axis_spread(runner: Runner, course: float) -> float:
    """Distance of a 1 m MOVE at 0.3 m/s on ``course`` from the idle wheels' least resistant position
    less that from their most resistant one (half a pitch on), m."""
    got = []
    for phase in (0.0, 0.5):
        sim = runner.client.link.device.sim  # type: ignore[attr-defined]
        pitch = 2.0 * math.pi / runner.robot.wheels[0].rollers.count
        for i in runner.geometry.idle_wheels(course):
            sim.physics.wheel_angle[0, i] = (round(sim.physics.wheel_angle[0, i] / pitch) + phase) * pitch
        r = runner.move("spread", 1.0, 0.3, course, "spread")
        assert r.truth is not None and r.truth.distance is not None
        got.append(r.truth.distance)
    return got[0] - got[1]


def carpet_tables() -> CalibrationSpec:
    return load_calibration(DATA / "omni4_carpet_calibration_before_idle_phase.yaml").for_surface("carpet")


def test_set_idle_phase_puts_the_first_idle_wheel_where_asked(omni4: RobotDescription) -> None:
    with carpet_runner(omni4) as runner:
        runner.client.upload_calibration(carpet_tables())
        geo = runner.geometry
        loss = 0.0
        for course, target in ((0.0, 0.3), (90.0, 0.8), (0.0, 0.55)):
            loss = set_idle_phase(runner, course, target, loss)
            runner.client.sleep(0.1)
            counts = runner.tap.counts()
            assert counts is not None
            i = geo.idle_wheels(course)[0]
            phase = (counts[i] % geo.roller_pitch[i]) / geo.roller_pitch[i]
            assert abs((phase - target + 0.5) % 1.0 - 0.5) < 0.15
        # a short open-loop ROTATE on carpet falls short by about a third of a pitch (4 degrees): the
        # first call learns it with a second ROTATE, the later ones ask for it at once
        assert 0.2 < loss < 0.5
        turns = [r for r in runner.log if r.group == f"{GROUP}:phase"]
        assert len(turns) == 4 and all(r.truth is not None for r in turns)
        # a rotation in place: the robot stays where it stood
        assert all(math.hypot(r.truth.x or 0.0, r.truth.y or 0.0) < 0.005 for r in turns if r.truth)


def test_moves_at_chosen_phases_make_the_axis_courses_independent_of_the_idle_wheels(
    omni4: RobotDescription,
) -> None:
    """The nominal omni4's default carpet tables (before: the drag runs' term, the wrong size and
    phase, fitted on the carpet of 4x wood's roller drag) on axis MOVEs at 0.3 m/s: the idle wheels'
    position moves them by 3-12 % with that term (26-36 % on that carpet). Once the slowest coast
    MOVEs have measured each wheel's drag, course 0 moves by under 2 % (measured 1.5 %, from 12.4);
    course 90 stays at 3.1 %, the same to 1e-14 with either term: both give its two MOVEs the same
    powers (on this carpet the swing is about 2 PWM counts; not yet understood, see the commit)."""
    spec = carpet_tables()
    assert spec.rollers is not None
    fit = RollerFit(spec.rollers.cos, spec.rollers.sin, 0.007, (0.5,), (0.0,), 48, 0.03, 0.001, True)
    with carpet_runner(omni4) as runner:
        runner.client.upload_calibration(spec)
        before = [axis_spread(runner, c) for c in (0.0, 90.0)]
        tuning = tune_coast(runner, spec, fit, (0.3,), 1.0, rounds=4, slow_rounds=8)
        assert tuning is not None and tuning.cos is not None and tuning.sin is not None
        assert tuning.gains == (1.0,) and tuning.table.y == (0.0, 0.0)
        # the simulator's rollers: every wheel alike, least drag at angle 0 (the encoders' origin), a
        # swing of +-0.14 N per wheel on carpet (1.8x wood's drag), about 2 PWM counts of the two
        # driving motors
        for c, s in zip(tuning.cos, tuning.sin, strict=True):
            assert -2.5 < c < -1.5 and abs(s) < 0.4
        tuned = RollerDragSpec(cos=tuning.cos, sin=tuning.sin, coast=tuning.table)
        runner.client.upload_calibration(spec.model_copy(update={"rollers": tuned}))
        after = [axis_spread(runner, c) for c in (0.0, 90.0)]
    assert max(before) > 0.1
    assert abs(after[0]) < 0.02 and abs(after[1]) <= abs(before[1]) + 1e-9, (before, after)


def test_the_probe_is_as_large_as_the_largest_wheels_drag_with_each_wheels_phase() -> None:
    drag = RollerDragSpec(
        cos=(-0.8, -3.0, 0.0, 0.0),
        sin=(-0.6, -4.0, 0.0, 1.0),
        coast=PiecewiseLinear(x=(0.0, 0.3), y=(0.0, -1.2)),
    )
    probe = probe_drag(drag)
    assert probe.coast is None  # gain 1: the counts the term adds are the counts uploaded
    amps = [math.hypot(c, s) for c, s in zip(probe.cos, probe.sin, strict=True)]
    assert amps == pytest.approx([5.0, 5.0, 0.0, 5.0], abs=0.01)
    assert probe.cos[0] / probe.sin[0] == pytest.approx(0.8 / 0.6, rel=0.01)  # its own phase
    none = RollerDragSpec(cos=(0.0,) * 4, sin=(0.0,) * 4)
    assert probe_drag(none).cos == (0.0,) * 4
