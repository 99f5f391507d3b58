"""Acceptance (issue 5): calibrate a robot whose true parameters differ from its description.

The firmware is built for the nominal omni4; the simulator drives omni4 with wheel radius +5 % and
motor torque constants +-10 % (``perturb.ACCEPTANCE``), in lockstep with a fixed seed, on wood and on
carpet. Open-loop MOVEs of 1 m on courses 0..90 (and back on course + 180) at 0.30..0.90 m/s, and
ROTATEs, are measured before and after calibration, and with the average of both surfaces.

What the simulator makes of the floor, stated once (docs/calibration.md has the numbers):

* on courses within about 20 degrees of a motor axis two wheels hardly turn, and their rollers'
  resistance depends on where the wheel happens to stand (seed 000: "can vary K_l as much as
  twice"); no open-loop power factor can know that, so single MOVEs there scatter around the fitted
  average (a few % on wood, 10-20 % on carpet);
* courses 30..60 degrees, where every wheel rolls, are what the power calibration controls: there
  MOVEs land within 3 % on average and within 4.5 % each on both floors (one folded K_l curve
  serves four directions that the unequal motors make differ by a few %).
"""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from omnibot.calibration.accuracy import AccuracyPlan, AccuracyRow, summarize
from omnibot.calibration.calfile import load_calibration, write_calibration
from omnibot.calibration.experiments import Plan
from omnibot.calibration.perturb import ACCEPTANCE, perturbed_robot
from omnibot.calibration.report import accuracy_entries, write_report
from omnibot.calibration.session import CalibrationResult, calibrate
from omnibot.calibration.tables import summary_table
from omnibot.client.client import RobotClient
from omnibot.robot.description import RobotDescription, load_robot
from tests.calibration.conftest import sim_client

SEED = 3
PLAN = Plan(levels=7)
CHECK = AccuracyPlan(speeds=(0.3, 0.6, 0.9))
"""1 m MOVEs on courses 0, 15, ..., 90 and back, at the bottom, middle and top of the speed range."""


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
    return result, out, wall


def rows(result: CalibrationResult, label: str) -> list[AccuracyRow]:
    return dict(accuracy_entries(result))[label]


def moves(rs: list[AccuracyRow], lo: float = 0.0, hi: float = 90.0) -> list[AccuracyRow]:
    return [r for r in rs if r.kind == "move" and lo <= r.course_deg % 180.0 <= hi]


def test_the_robot_really_differs(outcome: tuple[CalibrationResult, Path, float]) -> None:
    result, _, _ = outcome
    before = summarize(rows(result, "before, carpet"))
    assert before.distance_mean is not None and before.distance_mean > 0.3  # the wood-fitted preset on carpet
    assert summarize(rows(result, "before, wood")).distance_mean > 0.04  # type: ignore[operator]


@pytest.mark.parametrize("surface", ["wood", "carpet"])
def test_after_within_3_percent(outcome: tuple[CalibrationResult, Path, float], surface: str) -> None:
    result, _, _ = outcome
    after = rows(result, f"after ({surface} calibration), {surface}")
    before = rows(result, f"before, {surface}")
    # where every wheel rolls: within 3 % on average; single moves a little more, since one folded
    # table serves four directions that the unequal motors make differ by a few %
    rolling = [abs(r.error or 0.0) for r in moves(after, 30.0, 60.0)]
    assert len(rolling) == 3 * 3 * 2
    assert statistics.fmean(rolling) < 0.025
    assert max(rolling) < 0.045
    # over all courses: near the motor axes the rollers' position scatters single moves
    everything = summarize(after).distance_mean
    was = summarize(before).distance_mean
    assert everything is not None and was is not None
    assert everything < (0.03 if surface == "wood" else 0.08)
    assert everything < was / (2 if surface == "wood" else 4)


def test_averaged_calibration_shows_the_surfaces_apart(
    outcome: tuple[CalibrationResult, Path, float],
) -> None:
    result, _, _ = outcome
    wood = statistics.fmean(r.error or 0.0 for r in moves(rows(result, "after (average calibration), wood")))
    carpet = statistics.fmean(
        r.error or 0.0 for r in moves(rows(result, "after (average calibration), carpet"))
    )
    # one table for both floors: too far on wood, too short on carpet (seed 000: up to 20 % apart)
    assert wood > 0.1 and carpet < -0.05


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
    assert before < 0.85
    assert after == pytest.approx(1.0, abs=0.03)


def test_wall_time(outcome: tuple[CalibrationResult, Path, float]) -> None:
    assert outcome[2] < 90.0  # about 40 s on the development machine
