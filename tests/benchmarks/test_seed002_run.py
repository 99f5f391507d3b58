"""Seed 002's run: the S, the description changes and the numbers a run is read for (no simulation:
the runs are the benchmark's)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks import seed002_run as bench
from omnibot.control.followers.base import PLAN_WHEEL_USE
from omnibot.control.reach import course_speed_bound
from omnibot.robot import RobotDescription, load_robot


def test_the_s_is_three_legs_and_two_half_circles_where_2_m_s_takes_3_m_s2() -> None:
    path = bench.s_path()
    assert pytest.approx(3.0) == bench.BRAKE and pytest.approx(4.0 / 3.0) == bench.RADIUS
    assert pytest.approx(bench.BRAKE) == bench.TURN**2 / bench.RADIUS
    assert path.length == pytest.approx(3 * bench.LEG + 2 * math.pi * bench.RADIUS, rel=1e-4)
    assert path.start == pytest.approx((0.0, 0.0, 0.0))
    assert path.end[:2] == pytest.approx((bench.LEG, 4 * bench.RADIUS), abs=1e-9)
    assert np.all(path.theta == 0.0)  # the heading held, as seed 002's gyro PID holds it
    (a0, a1), (b0, b1) = bench.turns()
    for start, end, centre in ((a0, a1, (bench.LEG, bench.RADIUS)), (b0, b1, (0.0, 3 * bench.RADIUS))):
        inside = (path.s > start + 0.05) & (path.s < end - 0.05)
        r = np.hypot(path.x[inside] - centre[0], path.y[inside] - centre[1])
        assert r == pytest.approx(bench.RADIUS, abs=1e-3)
    legs = (path.s < a0 - 0.01) | ((path.s > a1 + 0.01) & (path.s < b0 - 0.01)) | (path.s > b1 + 0.01)
    assert set(np.round(path.y[legs], 6)) == {0.0, round(2 * bench.RADIUS, 6), round(4 * bench.RADIUS, 6)}
    with pytest.raises(ValueError, match="positive leg"):
        bench.s_path(leg=0.0)


def drive(path_s: np.ndarray, v: np.ndarray, dt: float = 0.01) -> np.ndarray:
    """Arc length reached at each step with speeds ``v`` (m/s)."""
    return np.concatenate(([0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * dt)))


def seed_like_trace(offset_after_turn: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """The seed's run as numbers: 0 -> 5 m/s at 2.5 m/s^2, 5 -> 2 m/s at 3 m/s^2 into each turn,
    2 m/s through it, 2 -> 5 m/s after; a sideways ``offset_after_turn`` m for 1 m after turn 1."""
    path = bench.s_path()
    (a0, a1), (b0, b1) = bench.turns()
    dt, t, s, v = 0.01, [0.0], [0.0], [0.0]
    while s[-1] < path.length - 0.05:
        here = s[-1]
        ahead = min((x for x in (a0, b0) if x > here), default=math.inf)
        in_turn = a0 <= here <= a1 or b0 <= here <= b1
        brake_from = ahead - (bench.TOP**2 - bench.TURN**2) / (2 * bench.BRAKE)
        if in_turn:
            target, accel = bench.TURN, 0.0
        elif here >= brake_from:
            target, accel = bench.TURN, -bench.BRAKE
        else:
            target, accel = bench.TOP, 2.5
        nv = v[-1] + accel * dt
        nv = min(nv, target) if accel > 0 else max(nv, target) if accel < 0 else target
        if here > b1 + 4.0:  # the end: a stop is not what is measured
            nv = v[-1]
        t.append(t[-1] + dt)
        v.append(nv)
        s.append(here + 0.5 * (v[-1] + v[-2]) * dt)
    arc = np.array(s)
    x, y = np.interp(arc, path.s, path.x), np.interp(arc, path.s, path.y)
    bump = (arc > a1) & (arc < a1 + 1.0)
    y = y - offset_after_turn * bump  # below the middle leg: off the path
    return np.array(t), np.column_stack((x, y))


def test_metrics_read_the_seeds_numbers_off_a_run() -> None:
    t, xy = seed_like_trace()
    m = bench.metrics(bench.s_path(), t, xy)
    assert m.peak == pytest.approx(bench.TOP, abs=0.02)
    assert m.pickup_to_top == pytest.approx((bench.TOP - 0.1) / 2.5, abs=0.08)
    assert m.turn_speed == pytest.approx([bench.TURN, bench.TURN], abs=0.02)
    for before, low, took in m.brake:  # from 98 % of 5 m/s to within 0.1 of 2 m/s at 3 m/s^2
        assert before == pytest.approx(bench.TOP, abs=0.02) and low == pytest.approx(bench.TURN, abs=0.02)
        assert took == pytest.approx((0.98 * bench.TOP - bench.TURN - 0.1) / bench.BRAKE, abs=0.08)
    assert m.rms < 1e-3 and m.max_error < 1e-3 and m.overshoot < 1e-3


def test_overshoot_is_the_error_in_and_after_a_turn() -> None:
    t, xy = seed_like_trace(offset_after_turn=0.05)
    m = bench.metrics(bench.s_path(), t, xy)
    assert m.overshoot == pytest.approx(0.05, abs=2e-3) and m.max_error == pytest.approx(0.05, abs=2e-3)
    second = bench.turns()[1:]  # the second turn alone: the bump is after the first
    assert bench.metrics(bench.s_path(), t, xy, second).overshoot < 1e-3
    with pytest.raises(ValueError, match="fewer than 3"):
        bench.metrics(bench.s_path(), t[:2], xy[:2])


def described(robot: RobotDescription) -> tuple[float, list[float], list[float]]:
    """What the variants change: the acceleration limit, each wheel's rollers' grip and gear."""
    grips = [w.rollers.grip for w in robot.wheels]
    return robot.limits.acceleration_max, grips, [w.motor.gear_ratio for w in robot.wheels]


def test_the_gear_that_plans_5_m_s_and_the_variants() -> None:
    robot = load_robot("omni3")
    before = described(robot)
    gear = bench.gear_needed(robot)
    assert gear < robot.wheels[0].motor.gear_ratio  # the preset plans at most 85 % of 5.32 m/s on course 0
    faster = bench.with_drive(robot, gear, robot.wheels[0].rollers.grip)
    assert PLAN_WHEEL_USE * course_speed_bound(faster, 0.0) == pytest.approx(bench.TOP, rel=0.01)
    changes = {"acceleration_max": 4.0, "gear_ratio": gear, "grip": 1.1}
    assert bench.variant("omni3", robot, changes) is robot
    accel = bench.variant("omni3+accel", robot, changes)
    assert (
        accel.limits.acceleration_max == 4.0
        and accel.wheels[0].motor.gear_ratio == robot.wheels[0].motor.gear_ratio
    )
    seed = bench.variant("omni3+seed", robot, changes)
    assert {w.rollers.grip for w in seed.wheels} == {1.1} and {w.motor.gear_ratio for w in seed.wheels} == {
        gear
    }
    assert described(robot) == before  # the copies changed nothing of the preset
    with pytest.raises(ValueError, match="no variant 'omni4'"):
        bench.variant("omni4", robot, changes)


def test_grip_needed_is_the_presets_when_it_already_holds() -> None:
    gentle = bench.with_limits(load_robot("omni3"), acceleration_max=0.2, angular_acceleration_max=0.2)
    assert bench.grip_needed(gentle) == gentle.wheels[0].rollers.grip
