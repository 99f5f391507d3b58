"""The fit residual's slip check: the studentised residual is a wheel's whole slip, quantisation
never passes the threshold, and a slip too slow for one interval builds up over the window."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from omnibot.estimation.estimator import PoseEstimator
from omnibot.estimation.odometry import WheelOdometry
from omnibot.estimation.wheelslip import MARGIN, WINDOW, WheelSlipCheck
from omnibot.robot import load_robot

PRESETS = ["omni4", "mecanum4"]


def per_count(preset: str) -> np.ndarray:
    robot = load_robot(preset)
    return np.array([2.0 * math.pi / e.counts_per_rev for e in robot.encoders.motors])


def counts_of(preset: str, twists: np.ndarray, slip: np.ndarray, dt: float = 0.01) -> np.ndarray:
    """Cumulative whole counts for body twists (n, 3) held ``dt`` s each, plus per-wheel slip (rad)
    added every interval: what encoders read (each within one count of its angle)."""
    J = np.asarray(load_robot(preset).wheel_matrix, dtype=float)
    angles = np.cumsum(twists @ J.T * dt + slip, axis=0)
    return np.vstack([np.zeros(J.shape[0]), np.floor(angles / per_count(preset))])


@pytest.mark.parametrize("preset", PRESETS)
def test_the_studentised_residual_is_a_wheels_whole_slip(preset: str) -> None:
    robot = load_robot(preset)
    J = np.asarray(robot.wheel_matrix, dtype=float)
    check = WheelSlipCheck(J, per_count(preset), window=0.0)
    angles = J @ np.array([0.004, -0.002, 0.01])
    angles[1] += 0.05  # wheel 1 slips by 0.05 rad beyond the body's motion
    residual = angles - J @ (np.linalg.pinv(J) @ angles)
    assert abs(residual[1]) == pytest.approx(0.25 * 0.05)  # the plain residual: a quarter of it
    check.update(angles, 0.01)
    assert check.slip[1] == pytest.approx(0.05)
    assert np.abs(check.slip) == pytest.approx(np.full(4, 0.05))  # one spare wheel: any could be it


@pytest.mark.parametrize("preset", PRESETS)
def test_the_threshold_is_the_quantisation_bound_and_rigid_motion_never_passes_it(preset: str) -> None:
    resolution = per_count(preset)
    check = WheelSlipCheck(load_robot(preset).wheel_matrix, resolution)
    assert check.threshold == pytest.approx(MARGIN * 4.0 * resolution.max())  # 4 counts, then the margin
    at = np.zeros(4)
    at[0] = check.threshold  # wheel 0 alone, by exactly the threshold (within rounding): not beyond it
    assert not WheelSlipCheck(load_robot(preset).wheel_matrix, resolution, window=0.0).update(at, 0.01)
    rng = np.random.default_rng(3)
    twists = rng.uniform(-1.0, 1.0, (3000, 3)) * [0.8, 0.8, 3.0]
    counts = counts_of(preset, twists, np.zeros(4))
    flagged = [check.update(d * resolution, 0.01) for d in np.diff(counts, axis=0)]
    assert not any(flagged)
    assert float(np.abs(check.slip).max()) <= 4.0 * resolution.max() + 1e-12


@pytest.mark.parametrize("preset", PRESETS)
def test_a_slip_too_slow_for_one_interval_builds_up_over_the_window(preset: str) -> None:
    """Wheel 1 slips by 1.2 counts every 10 ms (0.04 m/s at omni4's rim): one interval's residual
    is a quarter of that, under a count; the window finds it within its length."""
    resolution = per_count(preset)
    windowed = WheelSlipCheck(load_robot(preset).wheel_matrix, resolution)
    single = WheelSlipCheck(load_robot(preset).wheel_matrix, resolution, window=0.0)
    twists = np.tile([0.3, 0.1, 0.5], (100, 1))
    slip = np.zeros((100, 4))
    slip[50:, 1] = 1.2 * resolution[1]
    steps = np.diff(counts_of(preset, twists, slip), axis=0) * resolution
    flags = np.array([windowed.update(d, 0.01) for d in steps])
    assert not flags[:50].any()
    first = int(np.argmax(flags))
    assert 50 <= first <= 50 + round(WINDOW / 0.01)
    assert flags[first:].all()
    assert not any(single.update(d, 0.01) for d in steps)


def test_three_wheels_have_no_residual() -> None:
    robot = load_robot("omni3")
    check = WheelSlipCheck(robot.wheel_matrix, np.full(3, 1e-3))
    assert not check.redundant and check.threshold == 0.0
    assert not check.update([0.5, -0.2, 0.9], 0.01)


@dataclass(frozen=True)
class Sample:
    controller_time: float
    encoders: tuple[int, ...] | None
    tracking: tuple[int, ...] | None = None
    heading: float | None = None


def test_the_estimate_and_the_odometry_flag_one_slipping_wheel() -> None:
    """omni4 driving straight, wheel 1 slipping by 2 counts per 10 ms (0.07 m/s) from 0.5 s: the
    encoders-only estimate says so within the window and not before; before this check a slip had to
    reach 12 counts in one interval (its residual's quarter over 3 counts). WheelOdometry checks
    each update alone: 8 counts of one wheel are a slip there (2 in its plain residual)."""
    robot = load_robot("omni4")
    twists = np.tile([0.3, 0.0, 0.0], (100, 1))
    slip = np.zeros((100, 4))
    slip[50:, 1] = 2.0 * per_count("omni4")[1]
    counts = counts_of("omni4", twists, slip).astype(int)
    est = PoseEstimator(robot, translation="encoders", heading="encoders")
    flags = [est.update(Sample(0.01 * k, tuple(c))).slipping for k, c in enumerate(counts)]
    assert not any(flags[:51])
    assert all(flags[51 + round(WINDOW / 0.01) :])
    odo = WheelOdometry(robot)
    odo.update([0, 0, 0, 0])
    odo.update([10, 10, -10, -10])
    assert not odo.slipping
    odo.update([20, 28, -20, -20])
    assert odo.slipping


def test_the_heading_filter_is_told_only_of_a_skid() -> None:
    """Wheels 0 and 1 slipping 2 counts per 10 ms each way (no rotation in it: the gyro cannot see
    it): the estimate says so within the window, but the heading filter, told only of a gross slip in
    one interval (12 counts studentised, 3 in the plain residual), keeps trusting the wheels' rotation,
    which this slip does not touch."""
    robot = load_robot("omni4")
    resolution = per_count("omni4")
    assert np.linalg.pinv(robot.wheel_matrix)[2] @ np.array([1.0, -1.0, 0.0, 0.0]) == pytest.approx(0.0)
    twists = np.tile([0.3, 0.0, 0.0], (100, 1))
    slip = np.zeros((100, 4))
    slip[50:, :2] = np.array([2.0, -2.0]) * resolution[:2]
    counts = counts_of("omni4", twists, slip).astype(int)
    est = PoseEstimator(robot, translation="encoders")
    assert est.wheel_skid.threshold == pytest.approx(3.0 * 4.0 * resolution.max())
    told = []
    for k, c in enumerate(counts):
        estimate = est.update(Sample(0.01 * k, tuple(c), heading=0.0))
        told.append((estimate.slipping, est.filter.slipping))
    assert not any(s for s, _ in told[:51])
    assert all(s for s, _ in told[51 + round(WINDOW / 0.01) :])
    assert not any(f for _, f in told)


@pytest.mark.parametrize("window", [0.0, WINDOW])
def test_one_interval_sums_as_the_window_of_several_does(window: float) -> None:
    """A window of one interval (wheel odometry's window 0) skips the list sum and gives its numbers
    bit for bit, negative zeros among the increments included."""
    J = load_robot("omni4").wheel_matrix
    check = WheelSlipCheck(J, per_count("omni4"), window=window)
    steps = [
        np.array([-0.0, 0.0, 2e-3, -0.0]),
        np.full(4, -0.0),
        np.array([1e-3, -0.0, -2e-3, 5e-4]),
        np.zeros(4),
    ]
    for k, step in enumerate(steps):
        check.update(step, 0.01 if window else 0.0)
        summed = steps[: k + 1] if window else steps[k : k + 1]  # 0.1 s holds them all
        expected = check.student @ np.sum(summed, axis=0)
        assert check.slip.tobytes() == expected.tobytes()
