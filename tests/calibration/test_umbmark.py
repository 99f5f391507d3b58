"""UMBmark adapted to omni robots: the closed form and the path fit on synthetic squares."""

from __future__ import annotations

import math

import pytest

from omnibot.calibration.runs import Motion
from omnibot.calibration.umbmark import Increment, corrected_robot, fit_squares, integrate, umbmark
from omnibot.estimation import WheelOdometry
from omnibot.robot import RobotDescription

SIDE = 1.0


def square(ccw: bool, steps: int = 50) -> list[Increment]:
    """Odometry increments of an ideal square: 4 legs on course 0 and 4 quarter turns."""
    turn = (math.pi / 2 if ccw else -math.pi / 2) / steps
    out: list[Increment] = []
    for _ in range(4):
        out += [(SIDE / steps, 0.0, 0.0)] * steps
        out += [(0.0, 0.0, turn)] * steps
    return out


def truth_of(incs: list[Increment], radius: float, rotation: float, drift: float) -> Motion:
    """Where the robot really went when odometry reads ``incs`` (the error model applied)."""
    end = integrate(incs, radius, rotation, drift)
    return Motion(x=end.x, y=end.y, theta=end.theta)


@pytest.mark.parametrize(("rotation", "drift"), [(1.03, 0.0), (1.0, 0.02), (0.98, -0.015)])
def test_closed_form_recovers_corner_and_leg_errors(rotation: float, drift: float) -> None:
    errors = {}
    for ccw in (True, False):
        incs = square(ccw)
        t = truth_of(incs, 1.0, rotation, drift)
        o = integrate(incs)
        assert t.x is not None and t.y is not None
        errors[ccw] = (t.x - o.x, t.y - o.y)
    got = umbmark(errors[True], errors[False], SIDE)
    # A = (pi / 2) eps per corner; B = the turn odometry misses on each 1 m leg (linearised: a few %)
    assert got.corner_error == pytest.approx(math.pi / 2 * (rotation - 1.0), abs=2e-3)
    assert got.leg_turn == pytest.approx(drift * SIDE, abs=2e-3)
    assert got.rotation_scale == pytest.approx(rotation, abs=2e-3)


def test_path_fit_is_exact_on_its_own_model() -> None:
    truths = [(square(ccw), truth_of(square(ccw), 1.04, 1.03, 0.02)) for ccw in (True, False)]
    fitted = fit_squares(truths, 1.04, 1.0, SIDE)
    assert fitted is not None
    assert fitted == pytest.approx((1.03, 0.02), abs=1e-6)
    assert fit_squares(truths[:1], 1.04, 1.0, SIDE) is None  # one square cannot separate the errors


def test_distance_scale_cancels_round_a_square() -> None:
    # UMBmark's premise: a closed square hides the distance scale; a straight run is needed for it
    incs = square(True)
    a, b = integrate(incs, 1.0), integrate(incs, 1.1)
    assert math.hypot(a.x - b.x, a.y - b.y) < 1e-9


def test_corrected_robot_scales_odometry(omni4: RobotDescription) -> None:
    fixed = corrected_robot(omni4, 1.05, 0.98)
    assert fixed.wheels[0].radius == pytest.approx(0.025 * 1.05)
    assert fixed.wheels[0].position == pytest.approx((0.096 * 0.98, 0.0))
    # the same encoder counts: distance x1.05, rotation x1.05 / 0.98
    counts = [0, 440, 0, -440]  # one wheel turn of m2 forward and m4 backward: course 0
    spin = [440, 440, 440, 440]
    for robot, d_scale, w_scale in ((omni4, 1.0, 1.0), (fixed, 1.05, 1.05 / 0.98)):
        odo = WheelOdometry(robot)
        odo.update([0, 0, 0, 0])
        p = odo.update(counts)
        assert p.x == pytest.approx(2 * math.pi * 0.025 * d_scale)
        odo2 = WheelOdometry(robot)
        odo2.update([0, 0, 0, 0])
        assert odo2.update(spin).theta == pytest.approx(2 * math.pi * 0.025 / 0.096 * w_scale)
