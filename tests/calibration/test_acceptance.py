"""Acceptance (issue 5): calibrate a robot whose true parameters differ from its description.

The firmware is built for the nominal omni4; the simulator drives omni4 with wheel radius +5 % and
motor torque constants +-10 % (``perturb.ACCEPTANCE``), in lockstep with a fixed seed, on wood and on
carpet. Open-loop MOVEs of 1 m on courses 0..90 (and back on course + 180) at 0.30..0.90 m/s, and
ROTATEs, are measured before and after calibration, and with the average of both surfaces.

The calibration fits a motor map first (each motor's dead-band offset, its torque constant from a
stand test with the wheels lifted, and a gain with its speed term that balance the motors), then the
idle wheels' roller drag, then seed 000's factor tables through them.
What the simulator makes of the floor, stated once (docs/calibration.md has the numbers):

* on courses 0 and 90 two wheels do not turn at all, and their rollers' resistance depends on where
  each wheel stands (seed 000: "can vary K_l as much as twice"): 20 % of a MOVE between the least and
  the most resistant position on carpet. The controller reads those wheels' positions from their encoders and makes up for the
  drag (:func:`test_roller_drag_term_takes_out_the_wheel_position`);
* this robot's weak motors cannot power 1 m MOVEs at 0.9 m/s on every course (the 45 degree course
  needs 1 + 45/80 times an axis course's power, as seed 000's firmware says), and before that the
  drivers' current limit turns the body next to the diagonals: the calibration drives MOVEs at what
  the tables can power and slows them until they land, per folded course (its reach: wood 1.0 / 0.76
  / 0.6 / 0.76 m/s on courses 0 / 15 / 30 / 45, carpet 1.0 / 0.72 / 0.54 / 0.66), and the controller
  runs a MOVE asked faster at the reach (warning 18).
"""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

from omnibot.calibration.accuracy import AccuracyPlan, AccuracyRow, summarize, within_reach
from omnibot.calibration.calfile import load_calibration, write_calibration
from omnibot.calibration.motorfit import emf_counts
from omnibot.calibration.patterns import Geometry
from omnibot.calibration.perturb import ACCEPTANCE, perturbed_robot
from omnibot.calibration.plan import Plan
from omnibot.calibration.report import accuracy_entries, write_report
from omnibot.calibration.results import CalibrationResult, SurfaceSession
from omnibot.calibration.session import calibrate
from omnibot.calibration.tables import summary_table
from omnibot.calibration.verdict import judge_calibration
from omnibot.client import RobotClient
from omnibot.robot import RobotDescription, load_robot
from tests.calibration.conftest import sim_client

SEED = 3
PLAN = Plan(levels=7)
CHECK = AccuracyPlan(speeds=(0.3, 0.6, 0.9))
"""1 m MOVEs on courses 0, 15, ..., 90 and back, at the bottom, middle and top of the speed range."""

pytestmark = pytest.mark.timeout(1800)
"""The module's calibration (its fixture) takes about 25 s alone, minutes on a loaded machine (over 600 s
beside three other workers at load 15-28); how long it takes is a benchmark's business, not a test's."""


@pytest.fixture(scope="module")
def nominal() -> RobotDescription:
    return load_robot("omni4")


@pytest.fixture(scope="module")
def true_robot(nominal: RobotDescription) -> RobotDescription:
    return perturbed_robot(nominal, ACCEPTANCE)


@pytest.fixture(scope="module")
def outcome(
    nominal: RobotDescription, true_robot: RobotDescription, tmp_path_factory: pytest.TempPathFactory
) -> tuple[CalibrationResult, Path, float]:
    @contextmanager
    def open_client(surface: str) -> Iterator[RobotClient]:
        with sim_client(nominal, surface, true_robot=true_robot, seed=SEED) as client:
            yield client

    start = time.monotonic()
    result = calibrate(nominal, ["wood", "carpet"], open_client, truth="sim", plan=PLAN, accuracy=CHECK)
    wall = time.monotonic() - start
    out = tmp_path_factory.mktemp("acceptance")
    write_calibration(out / "cal.yaml", result)
    write_report(result, out / "report")
    print(f"\nacceptance: {wall:.1f} s wall\n" + summary_table(accuracy_entries(result)))
    for s in result.sessions:
        within = in_reach(s, moves(s.after or []))
        errors = [abs(r.error or 0.0) for r in within]
        print(
            f"{s.surface}: reach {s.spec.reach} m/s, {len(within)} MOVEs within it: max {max(errors, default=0):.4f}, "
            f"mean {statistics.fmean(errors) if errors else 0:.4f}; motors {s.spec.motors}"
        )
    return result, out, wall


def rows(result: CalibrationResult, label: str) -> list[AccuracyRow]:
    return dict(accuracy_entries(result))[label]


def moves(rs: list[AccuracyRow], lo: float = 0.0, hi: float = 90.0) -> list[AccuracyRow]:
    return [r for r in rs if r.kind == "move" and lo <= r.course_deg % 180.0 <= hi]


FOLD = Geometry.of(load_robot("omni4")).fold


def in_reach(session: SurfaceSession, rs: list[AccuracyRow], within: bool = True) -> list[AccuracyRow]:
    """The MOVEs asked no faster (``within``; else: faster) than the floor's reach on their course."""
    return [r for r in rs if within_reach(r, session.spec.reach, FOLD) is within]


def test_the_robot_really_differs(outcome: tuple[CalibrationResult, Path, float]) -> None:
    result, _, _ = outcome
    before = summarize(rows(result, "before, carpet"))
    # the wood-fitted preset on carpet (measured 11.5 %; 4x wood's roller drag made it 30 % and more)
    assert before.distance_mean is not None and before.distance_mean > 0.08
    assert summarize(rows(result, "before, wood")).distance_mean > 0.04  # type: ignore[operator]


def test_after_within_3_percent(outcome: tuple[CalibrationResult, Path, float]) -> None:
    """Within each floor's reach the calibrated MOVEs land within 3 % on every course and speed in
    reach (measured wood 1.1 %, mean 0.4 %; carpet 2.2 %, mean 0.7 %, and
    :func:`test_carpet_goal_within_3_percent`). The reach per folded course is what MOVEs at it
    really achieve (docs/calibration.md, the reach): below what the tables can power where the
    drivers' current limit turns the body (wood and carpet, courses next to 45 degrees). Beyond it the
    controller runs the MOVE at the reach."""
    result, _, _ = outcome
    wood, carpet = result.sessions
    for session in (wood, carpet):
        reach = session.spec.reach
        assert reach is not None and reach.courses_deg == (0.0, 15.0, 30.0, 45.0)
        assert session.reach == min(reach.speed)
        moves_ = session.reach_moves
        assert moves_ is not None and all(
            v is not None and c is not None and v <= c
            for c, v in zip(moves_.computed.values(), reach.speed, strict=True)
        )
    # measured within 2 % (Plan.reach_goal): wood 1.0 / 0.76 / 0.6 / 0.76 m/s, carpet 1.0 / 0.72 /
    # 0.54 / 0.66 (computed from the PWM: wood 1.0 / 0.93 / 0.81 / 0.88, carpet 1.0 / 0.84 / 0.73 /
    # 0.81; on the carpet of 4x wood's roller drag 0.66 / 0.51 / 0.35 / 0.49, its axes short of grip)
    assert wood.spec.reach is not None and carpet.spec.reach is not None
    assert wood.spec.reach(0.0) >= 0.9 and 0.55 <= wood.spec.reach(30.0) <= 0.72
    assert carpet.spec.reach(0.0) >= 0.9 and 0.3 <= carpet.spec.reach(30.0) < carpet.spec.reach(0.0)
    for session in (wood, carpet):
        surface = session.surface
        after = rows(result, f"after ({surface} calibration), {surface}")
        before = summarize(rows(result, f"before, {surface}"))
        summary = summarize(after)
        assert summary.moves == 42
        assert summary.distance_mean is not None and before.distance_mean is not None
        assert summary.distance_mean < before.distance_mean / 5  # measured / 17 (wood), / 14 (carpet)
        # every MOVE within the floor's reach on its course, on every course 0..90 and back
        within = in_reach(session, moves(after))
        # measured 32 on wood, 28 on carpet
        assert len(within) >= 18
        assert max(abs(r.error or 0.0) for r in within) < 0.03
        if surface == "wood":
            assert statistics.fmean(abs(r.error or 0.0) for r in within) < 0.015
        assert not any(r.warned or r.clamped for r in within)
        # beyond it the controller runs the MOVE at the reach (warning 18) and it lands: no MOVE falls
        # short any more, warned or not (before the reach step: wood's 15 and 75 out at 0.9 m/s 16 %
        # short with warning 17, carpet's axes 7.5-8 % short unwarned). Measured within 1.5 % on wood,
        # 1.9 % on carpet
        beyond = in_reach(session, moves(after), within=False)
        assert beyond and all(r.clamped for r in beyond)  # measured 10 on wood, 14 on carpet
        assert max(abs(r.error or 0.0) for r in beyond) < (0.03 if surface == "wood" else 0.05)


def test_carpet_goal_within_3_percent(outcome: tuple[CalibrationResult, Path, float]) -> None:
    """Issue 17's goal: carpet's MOVEs within its reach land within 3 % (measured 2.2 %, mean 0.7 %;
    on the carpet of 4x wood's roller drag, with the wheels started at five other angles 2.2-3.5 %,
    ``benchmarks.motor_model --wheels N``, docs/calibration.md), and keep their course better than
    before calibrating on the same MOVEs (measured 8.5 -> 3.5 degrees mean). The motor map's speed
    terms come from the stand test's torque constants, K_l's slow end from MOVEs at 0.3 m/s
    (docs/calibration.md)."""
    result, _, _ = outcome
    carpet = result.sessions[1]
    after = rows(result, "after (carpet calibration), carpet")
    within = in_reach(carpet, moves(after))
    assert max(abs(r.error or 0.0) for r in within) < 0.03
    # the course within the reach
    keys = {(r.course_deg, r.speed) for r in within}
    before = [r for r in moves(rows(result, "before, carpet")) if (r.course_deg, r.speed) in keys]
    course_after = summarize(within).course_mean_deg
    course_before = summarize(before).course_mean_deg
    assert course_after is not None and course_before is not None
    assert course_after < 0.7 * course_before


def test_motor_map_balances_unequal_motors(
    outcome: tuple[CalibrationResult, Path, float], nominal: RobotDescription
) -> None:
    """Measured: gains within 0.029 on carpet, 0.036 on wood; speed terms within 3.1 and 4.0 counts
    per m/s (docs/calibration.md)."""
    result, _, _ = outcome
    for session in result.sessions:
        motors = session.spec.motors
        assert motors is not None
        # m2 and m3 are 10 % weaker (torque constant 0.9): they need the larger offsets
        assert min(motors.offset[1], motors.offset[2]) > max(motors.offset[0], motors.offset[3])
        balance = session.fit.balance
        assert balance is not None and len(balance.powers) >= 3
        # the map balances every power below the top (measured wood 0.28 -> 0.05 rad rms summed); at
        # the top the drivers limit the current and no map balances the runs (0.59 -> 0.57 on wood,
        # 0.96 -> 0.95 on carpet): it must not make them worse
        assert sum(balance.after[:-1]) < 0.7 * sum(balance.before[:-1])
        assert balance.after[-1] <= balance.before[-1]
        # the two numbers per motor: the stand test's torque constants s (geometric mean 1: the common
        # share is the K_l tables'), the gains 1/s and speed terms (s - 1/s) E they need
        s = np.array([1.1, 0.9, 0.9, 1.1])
        s /= np.exp(np.mean(np.log(s)))
        assert balance.stand is not None and balance.stand.torque == pytest.approx(s, abs=0.005)
        assert [g(100.0) for g in motors.gain] == pytest.approx(1 / s, abs=0.06)
        assert motors.speed == pytest.approx((s - 1 / s) * np.array(emf_counts(nominal)), abs=7.0)
        before = summarize(rows(result, f"before, {session.surface}"))
        after = summarize(session.after or [])
        # the weak side pair no longer stalls on courses 15..30: the robot keeps its course better on
        # wood (measured 7.8 -> 2.3 degrees); on carpet within the reach (test_carpet_goal_within_3_percent)
        assert after.course_mean_deg is not None and before.course_mean_deg is not None
        if session.surface == "wood":
            assert after.course_mean_deg < 0.7 * before.course_mean_deg


def test_roller_drag_term_takes_out_the_wheel_position(
    outcome: tuple[CalibrationResult, Path, float], nominal: RobotDescription, true_robot: RobotDescription
) -> None:
    """The same MOVE on course 90 (wheels m2 and m4 idle) with the idle wheels at their least and
    most resistant positions (half a roller pitch apart): 20 % apart without the controller's drag
    term, within 6 % with it (measured 1.2 %; 1.0 % on 2026-12-02, the drag from the drag runs and from
    MOVEs at chosen idle phases alike: on this robot the drag runs' fit was right, on the nominal
    one it was not, tests/calibration/test_rollers.py)."""
    result, _, _ = outcome
    carpet = result.sessions[1].spec
    fit = result.sessions[1].fit.rollers
    assert carpet.rollers is not None and fit is not None and fit.kept
    assert fit.rms_after < 0.1 * fit.rms_before
    pitch = 2 * math.pi / true_robot.wheels[1].rollers.count
    spread = {}
    for label, spec in (("with", carpet), ("without", carpet.model_copy(update={"rollers": None}))):
        got = []
        with sim_client(nominal, "carpet", true_robot=true_robot, seed=SEED + 2) as client:
            sim = client.link.device.sim  # type: ignore[attr-defined]
            client.upload_calibration(spec)
            for k, phase in enumerate((0.0, 0.5 * pitch, 0.0, 0.5 * pitch)):
                angles = sim.physics.wheel_angle
                for j in (1, 3):
                    angles[0, j] = round(angles[0, j] / pitch) * pitch + phase
                x0, y0 = sim.pose.x, sim.pose.y
                client.move(1.0, 0.3, math.radians(90 + 180 * (k % 2)))
                client.wait_idle(timeout=10)
                client.sleep(0.5)
                got.append(math.hypot(sim.pose.x - x0, sim.pose.y - y0))
        low, high = got[0::2], got[1::2]
        assert low[0] == pytest.approx(low[1], abs=0.01) and high[0] == pytest.approx(high[1], abs=0.01)
        spread[label] = low[0] - high[0]
    # more than 15 % of the distance from the wheels' position alone (measured 20.4 %; 30 % and more
    # on the carpet of 4x wood's roller drag)
    assert spread["without"] > 0.15
    assert abs(spread["with"]) < 0.06
    # the MOVEs' coast: the faster the MOVE, the more the drag outlasts it and the more power it needs
    tuning = result.sessions[1].fit.coast
    assert tuning is not None and len(tuning.speeds) == 4
    # up to 90 % of the axes' computed reach (carpet 1.0 m/s: measured 0.9), where the axis MOVEs run
    # up to their driven reach, not of the slowest course's (0.56: 0.50, and held beyond)
    assert tuning.speeds[-1] > 0.7
    # mu falls with speed overall; neighbouring speeds' least-squares fits may cross by a few %
    assert tuning.gains[-1] > tuning.gains[0] and tuning.power[0] > max(tuning.power[1:])
    assert tuning.power[-1] < 0.9 * tuning.power[0]


def test_averaged_calibration_shows_the_surfaces_apart(
    outcome: tuple[CalibrationResult, Path, float],
) -> None:
    result, _, _ = outcome
    wood = statistics.fmean(r.error or 0.0 for r in moves(rows(result, "after (average calibration), wood")))
    carpet = statistics.fmean(
        r.error or 0.0 for r in moves(rows(result, "after (average calibration), carpet"))
    )
    # one table for both floors: too far on wood, too short on carpet (seed 000: up to 20 % apart;
    # measured +4.9 % and -3.7 %)
    assert wood > 0.03 and carpet < -0.02


def test_gyro_and_odometry(outcome: tuple[CalibrationResult, Path, float]) -> None:
    result, _, _ = outcome
    wood = result.sessions[0]
    assert wood.gyro is not None and wood.gyro.scale is not None
    assert wood.odometry is not None
    odo = wood.odometry
    # true radius +5 %: odometry sees 5 % less distance (minus a little slip) and rotation
    assert 1.02 < odo.wheel_radius_scale < 1.06
    assert odo.rotation_scale == pytest.approx(1.05, abs=0.005)
    assert odo.wheel_base_scale == pytest.approx(1.0, abs=0.03)
    assert odo.square_rotation_scale == pytest.approx(1.05, abs=0.01)
    assert odo.return_error_before is not None and odo.return_error_after is not None
    assert odo.return_error_after < 0.5 * odo.return_error_before


def test_the_file_uploads_and_applies(
    outcome: tuple[CalibrationResult, Path, float], nominal: RobotDescription, true_robot: RobotDescription
) -> None:
    result, out, _ = outcome
    cal = load_calibration(out / "cal.yaml")
    assert cal.calibration == result.chosen
    assert set(cal.surfaces) == {"wood", "carpet"} and cal.gyro is not None and cal.odometry is not None
    assert {p.name for p in (out / "report").iterdir()} >= {"fig5_rates.png", "fig6_kt_kr.png", "fig7_kl.png"}
    with sim_client(nominal, "carpet", true_robot=true_robot, seed=SEED + 1) as client:
        sim = client.link.device.sim  # type: ignore[attr-defined]
        client.move(1.0, 0.5, math.radians(45))
        client.wait_idle(timeout=10)
        client.sleep(0.5)
        before = math.hypot(sim.pose.x, sim.pose.y)
        client.upload_calibration(cal.for_surface("carpet"))
        x0, y0 = sim.pose.x, sim.pose.y
        client.move(1.0, 0.5, math.radians(225))
        client.wait_idle(timeout=10)
        client.sleep(0.5)
        after = math.hypot(sim.pose.x - x0, sim.pose.y - y0)
    assert before < 0.9  # measured 0.867 m: the preset's tables on the weak carpet robot at 45 degrees
    assert after == pytest.approx(1.0, abs=0.03)


def test_the_verdict_keeps_each_floors_tables_and_the_average(
    outcome: tuple[CalibrationResult, Path, float],
) -> None:
    """Each floor's own tables are better than before on every course and ROTATE; with the floors as
    far apart as seed 000's ("up to 20 %") the average is better than none on both too (measured wood
    7.7 -> 4.4 %, carpet 10.7 -> 3.5 % on the whole; each floor's own 0.6 and 0.8 %), so it is kept as
    seed 000 kept it. (On the carpet of 4x wood's roller drag it made every wood course but 15 and 75
    worse, wood 7.7 -> 16.9 %, and was not kept.)"""
    result, _, _ = outcome
    verdict = judge_calibration(result)
    assert verdict.better is True and verdict.worse == ()
    assert verdict.average is not None and verdict.average.better is True and verdict.average.worse == ()
