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
from omnibot.robot import load_robot
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
    """Seed 000's motor pattern at power P: on a course of 0/90/180/270 degrees two opposite motors at
    +-P, on course 45 all four at +-P."""
    if course == 45:
        rim = kin.inverse(load_robot("omni4").wheel_matrix, (1.0, 1.0, 0.0))
        return np.asarray(power * rim / np.abs(rim).max())
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


@pytest.mark.parametrize(
    ("course", "powers"), [(0, [70, 100, 130, 160, 190, 220, 255]), (45, [80, 100, 130, 160, 190, 220, 255])]
)
def test_carpet_is_shorter_than_wood_by_at_most_the_seeds_20_percent(
    course: int, powers: list[float]
) -> None:
    """Seed 000: the floor makes "a difference up to 20 % for the motion distance" at the same power,
    over its series' powers (the axis from 70 counts, 45 degrees from 80). Carpet loses most near the
    start, where its rollers' drag is the larger share (14.6 % at 70 on the axis, 18.2 % at 80 at 45
    degrees), and 4-9 % from 130 counts up."""
    loss = 1.0 - seed000_distances(course, powers, "carpet") / seed000_distances(course, powers, "wood")
    assert ((loss > 0.03) & (loss < 0.20)).all(), loss


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


# --------------------------------------------------------------------------- seed 000's other two series

FIRMWARE_SHIFT = 40.0
"""OSLL omnibot v0.038's CALIBRATION_MOVE_SHIFT: the counts it adds to every motor's power."""


def steady_rim_speed(course: float | None, slopes: np.ndarray, surface: str = "wood") -> np.ndarray:
    """Steady rim speed (m/s) of the busiest wheel for each slope s, driven as OSLL omnibot v0.038 does.

    Every wheel with a rim speed u_i in the pattern gets sign(u_i) (40 + s |u_i| / max |u|) counts
    (the firmware's shift, then its linear part): ``course`` in degrees is a translation, None a
    rotation in place. One batch, 2.5 s, the mean over the last 0.5 s.
    """
    robot = load_robot("omni4")
    if course is None:
        twist = (0.0, 0.0, 1.0)
    else:
        twist = (math.cos(math.radians(course)), math.sin(math.radians(course)), 0.0)
    rim = kin.inverse(robot.wheel_matrix, twist)
    pattern = rim / np.abs(rim).max()
    pattern[np.abs(pattern) < 1e-9] = 0.0
    pwm = np.sign(pattern) * (FIRMWARE_SHIFT + np.outer(slopes, np.abs(pattern)))
    ph = Physics(robot, n=len(slopes), surfaces=(surface,))
    total = np.zeros(len(slopes))
    for k in range(2500):
        ph.step(pwm)
        if k >= 2000:
            total += np.abs(ph.wheel_speed).max(axis=1) * robot.wheels[0].radius
    return total / 500


def slope_for_rim_speed(course: float | None, speeds: Sequence[float]) -> np.ndarray:
    """The firmware's linear part (counts above the shift) the busiest wheel needs for each rim speed."""
    slopes = np.arange(0.0, 216.0, 5.0)
    rim = steady_rim_speed(course, slopes)
    moving = rim > 0.01
    return np.asarray(np.interp(speeds, rim[moving], slopes[moving]))


RIM_SPEEDS = (0.2, 0.3, 0.4, 0.5, 0.6)


@pytest.fixture(scope="module")
def axis_slope() -> np.ndarray:
    return slope_for_rim_speed(0.0, RIM_SPEEDS)


def test_45_degree_series_needs_the_firmware_s_56_percent_more(axis_slope: np.ndarray) -> None:
    """OSLL omnibot v0.038 drives a motor with 40 + K (1 + a/80) V sin(D + D_n) counts (a: course folded
    into 0..45): on the 45 degree course each wheel needs (1 + 45/80) = 1.5625 times the power above
    the shift that the same rim speed needs on a motor axis. Measured: 1.52 .. 1.64 over rim speeds
    0.2 .. 0.6 m/s (body 0.28 .. 0.85 m/s); without the combined rolling-and-driving drag it is 1.06."""
    ratio = slope_for_rim_speed(45.0, RIM_SPEEDS) / axis_slope
    assert np.all(np.abs(ratio - 1.5625) <= 0.1), ratio
    assert abs(ratio.mean() - 1.5625) <= 0.05, ratio


def test_the_factor_rises_from_the_axis_towards_45_degrees(axis_slope: np.ndarray) -> None:
    """Seed 000's Fig. 7: K_l rises towards 45 degrees; the firmware's 1 + a/80 is a straight line
    through 1.1875 at 15 and 1.375 at 30 degrees. Measured (mean over the rim speeds): 1.22, 1.45."""
    factors = [float(np.mean(slope_for_rim_speed(c, RIM_SPEEDS) / axis_slope)) for c in (15.0, 30.0, 45.0)]
    assert 1.0 < factors[0] < factors[1] < factors[2], factors
    # the model's sin(2 beta) weighting lies a little above the firmware's straight line in between
    assert abs(factors[0] - (1 + 15 / 80)) <= 0.06 and abs(factors[1] - (1 + 30 / 80)) <= 0.1, factors


def test_four_motors_sag_the_battery_more_than_two() -> None:
    """Battery sag: the 45 degree series draws on four motors, the axis series on two."""
    robot = load_robot("omni4")
    ph = Physics(robot, n=2)
    pwm = np.array([[0.0, 200.0, 0.0, -200.0], [200.0, 200.0, -200.0, -200.0]])
    for _ in range(2000):
        ph.step(pwm)
    sag = robot.battery.voltage - ph.battery_voltage
    assert 0.0 < sag[0] < sag[1], sag
    assert sag[1] > 1.5 * sag[0]


# --------------------------------------------------------------------------- seed 002: slowing down, coasting


def omni3_at_top_speed() -> tuple[Physics, np.ndarray]:
    """omni3 driven straight ahead at full power for 4 s (about 5.3 m/s), and its forward pattern."""
    robot = load_robot("omni3")
    w = kin.inverse(robot.wheel_matrix, (1.0, 0.0, 0.0))
    pattern = w / np.abs(w).max()
    ph = Physics(robot)
    for _ in range(4000):
        ph.step(255.0 * pattern)
    assert ph.twist[0, 0] > 5.0
    return ph, pattern


def seconds_until(ph: Physics, pwm: np.ndarray, speed: float, limit: float = 10.0) -> float:
    start = ph.time
    while ph.twist[0, 0] > speed:
        ph.step(pwm)
        assert ph.time - start < limit, f"still {ph.twist[0, 0]:.2f} m/s after {limit} s"
    return ph.time - start


def test_omni3_slows_from_5_to_2_m_per_s_in_about_1_s() -> None:
    """Seed 002: "decrease it's speed from 5m/sec to 2m/sec in 1 sec" with its speed loop. Commanding
    the power that holds 2 m/s (100 counts: 2.06 m/s steady) the drivers brake on the back-EMF; the
    speed is within 10 % of 2 m/s after 1.18 s (tolerance 0.8 .. 1.6 s)."""
    ph, pattern = omni3_at_top_speed()
    assert 0.8 <= seconds_until(ph, 100.0 * pattern, 2.2) <= 1.6


def test_omni3_coasts_far_with_its_drivers_off() -> None:
    """Seed 002's overshoot "due to slip, inertia and inability of motors to suddenly ... decelerate":
    with the drivers off only the wheels' friction stops 30 kg: 4.7 s and about 15 m from 5.3 to 2 m/s."""
    ph, pattern = omni3_at_top_speed()
    x0 = ph.pose[0, 0]
    assert 3.5 <= seconds_until(ph, 0.0 * pattern, 2.0) <= 6.0
    assert ph.pose[0, 0] - x0 > 10.0


# --------------------------------------------------------------------------- seed 003: its Fig. 4 patterns

FIG4 = {  # wheel powers in the preset's order (left_front, right_front, right_back, left_back)
    "forward": ([200, 200, 200, 200], 0.0),  # Fig. 4(a): all four wheels forward
    "left": ([-200, 200, -200, 200], 90.0),  # the diagonal pairs against each other
    "forward-left": ([0, 200, 0, 200], 45.0),  # one diagonal pair alone
}


@pytest.mark.parametrize("motion", sorted(FIG4))
def test_mecanum4_rollers_turn_seed003_s_patterns_into_its_directions(motion: str) -> None:
    """The wheel patterns of seed 003's Fig. 4, given as powers (not through the kinematics): the
    rollers' forces add up to motion in the figure's direction (within 3 degrees, no turn)."""
    powers, direction = FIG4[motion]
    ph = Physics(load_robot("mecanum4"))
    for _ in range(1000):
        ph.step(np.array(powers, dtype=float))
    x, y, theta = ph.pose[0]
    assert math.hypot(x, y) > 0.15
    assert abs(math.degrees(math.remainder(math.atan2(y, x) - math.radians(direction), math.tau))) < 3.0
    assert abs(theta) < 0.02
