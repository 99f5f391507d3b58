"""The simulator against the seed robots' measurements, with physically plausible parameters.

Seed 000's experiment (tests/data/omni4_straight_power_sweep.csv): from rest, two opposite motors at
+P and -P for 1000 ms, the other two unpowered. Course 0 drives m2 at +P and m4 at -P, course 90 m1
at +P and m3 at -P; courses 180 and 270 reverse the signs. Assumptions, stated here once:

* the floor is wood (the seed calibrated on wood and carpet; the reference table is taken as wood);
* the distance is the displacement of the body centre at the end of the 1000 ms of power, i.e. the
  "distance passed by the robot in one second" that seed 000's Fig. 5 plots as a rate in cm/s; the
  coast-down after the power goes off (the driver lets the motors free-wheel) is not included;
* every wheel starts at angle 0, the low-friction roller position seed 000 set its wheels to.

The seed robot was not symmetric (course 90 runs up to 17 % further than course 180 at the same
power); the simulated robot is, so one simulated curve must meet all four measured ones. It does,
within 15 % for every P >= 100 on all four courses.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pytest

from omnibot.robot import kinematics as kin
from omnibot.robot.description import load_robot
from omnibot.sim.physics import Physics

DATA = Path(__file__).parent.parent / "data" / "omni4_straight_power_sweep.csv"
COURSES = (0, 90, 180, 270)


def load_sweep() -> dict[int, dict[int, float]]:
    """{course: {power: distance in m}} for the measured entries of the CSV."""
    with DATA.open(encoding="utf-8") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    out: dict[int, dict[int, float]] = {c: {} for c in COURSES}
    for row in rows:
        for c in COURSES:
            cell = row[f"course_{c}_mm"].strip()
            if cell:
                out[c][int(row["power"])] = float(cell) / 1000.0
    return out


def seed000_pwm(course: int, power: float) -> np.ndarray:
    """Seed 000's motor pattern for a course of 0/90/180/270 degrees at power P."""
    pwm = np.zeros(4)
    sign = 1.0 if course in (0, 90) else -1.0
    a, b = (1, 3) if course in (0, 180) else (0, 2)
    pwm[a], pwm[b] = sign * power, -sign * power
    return pwm


def seed000_distances(course: int, powers: Sequence[float], surface: str = "wood") -> np.ndarray:
    """Simulated distance (m) after 1000 ms at each power, all powers in one batch."""
    ph = Physics(load_robot("omni4"), n=len(powers), surfaces=(surface,))
    pwm = np.array([seed000_pwm(course, p) for p in powers])
    for _ in range(1000):
        ph.step(pwm)
    return np.asarray(np.hypot(ph.pose[:, 0], ph.pose[:, 1]))


@pytest.fixture(scope="module")
def sweep() -> dict[int, dict[int, float]]:
    return load_sweep()


@pytest.fixture(scope="module")
def simulated(sweep: dict[int, dict[int, float]]) -> dict[int, dict[int, float]]:
    powers = sorted({p for c in COURSES for p in sweep[c]})
    out = {}
    for c in COURSES:
        d = seed000_distances(c, powers)
        out[c] = dict(zip(powers, d.tolist(), strict=True))
    return out


def test_the_data_file_is_the_seed_table(sweep: dict[int, dict[int, float]]) -> None:
    assert sweep[0][255] == pytest.approx(1.09) and sweep[90][70] == pytest.approx(0.15)
    assert len(sweep[0]) == 20 and len(sweep[180]) == 8


@pytest.mark.parametrize("course", COURSES)
def test_seed000_power_sweep_within_15_percent(
    course: int, sweep: dict[int, dict[int, float]], simulated: dict[int, dict[int, float]]
) -> None:
    errors = {p: simulated[course][p] / measured - 1.0 for p, measured in sweep[course].items() if p >= 100}
    assert errors
    worst = max(errors, key=lambda p: abs(errors[p]))
    assert abs(errors[worst]) <= 0.15, f"course {course}, P={worst}: {errors[worst]:+.1%}"


def test_the_robot_travels_in_the_commanded_direction(simulated: dict[int, dict[int, float]]) -> None:
    ph = Physics(load_robot("omni4"), n=4)
    pwm = np.array([seed000_pwm(c, 200) for c in COURSES])
    for _ in range(1000):
        ph.step(pwm)
    for i, c in enumerate(COURSES):
        heading = math.degrees(math.atan2(ph.pose[i, 1], ph.pose[i, 0]))
        assert abs(math.remainder(heading - c, 360)) < 0.1
        assert abs(ph.pose[i, 2]) < 1e-6


def test_dead_band_at_low_power(simulated: dict[int, dict[int, float]]) -> None:
    # linear extrapolation from the upper half of the sweep
    high = [p for p in simulated[0] if p >= 160]
    slope, offset = np.polyfit(high, [simulated[0][p] for p in high], 1)
    assert simulated[0][70] < 0.6 * (slope * 70 + offset)
    assert 0.05 < simulated[0][70] < 0.25  # but it does move, as measured (120-150 mm)
    # a power inside the dead band does not move the robot at all
    still = seed000_distances(0, [10, 20, 25, 30])
    assert still.max() < 1e-3


def test_carpet_is_clearly_shorter_than_wood() -> None:
    """Seed 000: up to 20 % less distance on carpet for the same power."""
    powers = [130, 160, 190, 220, 255]
    wood = seed000_distances(0, powers, "wood")
    carpet = seed000_distances(0, powers, "carpet")
    loss = 1.0 - carpet / wood
    assert ((loss > 0.10) & (loss < 0.25)).all(), loss


def test_omni3_reaches_5_m_per_s_in_about_2_s_with_wheel_slip() -> None:
    """Seed 002: "0 to its maximum speed of 5 m/sec which required 2 sec pickup time due to slip"."""
    robot = load_robot("omni3")
    w = kin.inverse(robot.wheel_matrix, (1.0, 0.0, 0.0))
    pwm = 255.0 * w / np.abs(w).max()  # straight ahead at full power
    ph = Physics(robot)
    t_45, slip_at_1s, top = None, 0.0, 0.0
    for _ in range(4000):
        ph.step(pwm)
        speed = math.hypot(ph.twist[0, 0], ph.twist[0, 1])
        top = max(top, speed)
        if t_45 is None and speed >= 4.5:
            t_45 = ph.time
        if abs(ph.time - 1.0) < 1e-9:
            slip_at_1s = float(np.abs(ph.slip[0]).max())
    assert top >= 4.5
    assert t_45 is not None and 1.4 <= t_45 <= 2.8
    assert slip_at_1s > 0.5  # the driven wheels spin well faster than the robot moves
    assert np.abs(ph.slip[0]).max() < 0.05  # and grip again at top speed
    assert top < 6.0
