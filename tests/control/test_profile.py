"""Time-optimal speed profile: closed-form cases, traction on curves, turns in place, caps."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.control.paths import MotionLimits, Path, standard_path, time_optimal_profile
from omnibot.control.paths.profile import MAX_SAMPLES, min_traversal_time
from omnibot.errors import ConfigError
from omnibot.robot import load_robot

LIM = MotionLimits(v_max=0.5, a_max=2.0, w_max=10.0, alpha_max=20.0)


def test_straight_line_trapezoid_and_triangle() -> None:
    line = Path.from_points([(0.0, 0.0), (1.0, 0.0)], theta=0.0)
    assert time_optimal_profile(line, LIM).min_time == pytest.approx(1.0 / 0.5 + 0.5 / 2.0, rel=1e-3)
    short = Path.from_points([(0.0, 0.0), (0.04, 0.0)], theta=0.0)  # never reaches v_max
    assert time_optimal_profile(short, LIM).min_time == pytest.approx(2 * math.sqrt(0.04 / 2.0), rel=1e-3)


def test_circle_speed_is_limited_by_grip() -> None:
    ring = standard_path("circle", size=1.0)  # radius 0.5: v <= sqrt(a_lat r) = 1 m/s
    fast = MotionLimits(v_max=3.0, a_max=2.0, w_max=10.0, alpha_max=20.0)
    prof = time_optimal_profile(ring, fast)
    assert prof.speed.max() == pytest.approx(1.0, rel=0.01)
    half = len(prof.t) // 2
    ref = prof.at(prof.t[half])
    assert math.hypot(ref.ax, ref.ay) == pytest.approx(2.0, rel=0.03)  # all the grip goes sideways


def test_turn_in_place_is_timed_by_the_angular_limits() -> None:
    turn = Path(np.zeros(2), np.zeros(2), np.array([0.0, math.pi / 2]))
    lim = MotionLimits(v_max=0.5, a_max=2.0, w_max=1.0, alpha_max=2.0)
    prof = time_optimal_profile(turn, lim)
    # bang-bang at alpha_max / 2 = 1 rad/s^2 capped at w_max = 1 rad/s: 1 s of ramps plus pi/2 - 1 at full rate
    assert prof.min_time == pytest.approx(math.pi / 2 + 1.0, rel=1e-3)
    mid = prof.at(prof.min_time / 2)
    assert (mid.x, mid.y, mid.speed) == (0.0, 0.0, 0.0)
    assert mid.w == pytest.approx(1.0) and mid.theta == pytest.approx(math.pi / 4, abs=1e-3)


def test_path_speed_caps_and_is_ignored_for_the_minimum_time() -> None:
    xs = np.linspace(0, 2, 201)
    slow = Path.from_points(np.column_stack((xs, 0 * xs)), theta=0.0, v=np.full(201, 0.2))
    prof = time_optimal_profile(slow, LIM)
    assert prof.speed.max() == pytest.approx(0.2, rel=1e-3)
    assert prof.min_time > 10.0
    assert min_traversal_time(slow, LIM) == pytest.approx(2.0 / 0.5 + 0.25, rel=1e-3)


def test_reference_is_continuous_and_ends_at_the_end() -> None:
    path = standard_path("s_curve", size=1.0, heading="tangent")
    prof = time_optimal_profile(path, MotionLimits.from_robot(load_robot("omni4"), 0.5))
    ts = np.linspace(0, prof.min_time, 500)
    refs = [prof.at(t) for t in ts]
    xy = np.array([(r.x, r.y) for r in refs])
    assert np.max(np.hypot(*np.diff(xy, axis=0).T)) < 0.5 * (ts[1] - ts[0]) * 1.05  # never faster than v_max
    assert path.distances(xy).max() < 1e-6
    end = prof.at(prof.min_time + 1.0)
    assert (end.x, end.y, end.speed) == pytest.approx((path.end[0], path.end[1], 0.0))
    assert max(abs(r.w) for r in refs) <= 10.0


def test_a_profile_needs_two_points() -> None:
    with pytest.raises(ValueError, match="two points"):
        time_optimal_profile(Path(np.zeros(1), np.zeros(1), np.zeros(1)), LIM)


def test_a_path_too_long_to_profile_is_refused_before_it_is_built() -> None:
    limits = MotionLimits(v_max=1.0, a_max=1.0, w_max=1.0, alpha_max=1.0)
    line = Path(np.array([0.0, 1e300]), np.zeros(2), np.zeros(2))  # would be 1e302 grid points
    with pytest.raises(ConfigError, match=r"too long to profile: 1e\+300 m .* at most 200,000; split it"):
        time_optimal_profile(line, limits)
    turns = np.arange(0.0, 21_000.0, 3.0)  # 3,300 turns in place: 2,100 m of sigma
    spin = Path(np.zeros(len(turns)), np.zeros(len(turns)), turns)
    with pytest.raises(ConfigError, match="too long to profile"):
        time_optimal_profile(spin, limits)
    just = MAX_SAMPLES * 0.01 / 4  # a quarter of the budget builds
    assert len(time_optimal_profile(Path(np.array([0.0, just]), np.zeros(2), np.zeros(2)), limits).t) > 1000
    with pytest.raises(ValueError, match="positive resolution"):
        time_optimal_profile(line, limits, resolution=0.0)


def test_course_rate_caps_the_turns_only_and_gives_way_to_the_time_budget() -> None:
    from dataclasses import replace

    from omnibot.control.paths.generator import figure_eight_path
    from omnibot.control.paths.profile import profile_within

    eight = figure_eight_path(2, length=10.0, radius_min=0.4, heading="fixed")
    fast = MotionLimits(v_max=1.0, a_max=2.0, w_max=10.0, alpha_max=20.0)
    free = time_optimal_profile(eight, fast)
    assert np.max(free.speed * np.abs(free.kappa)) > 1.0  # the lobes' ends turn the course fast
    capped = time_optimal_profile(eight, replace(fast, course_rate=0.8))
    assert np.max(capped.speed * np.abs(capped.kappa)) <= 0.8 * (1 + 1e-6)
    assert capped.speed.max() == pytest.approx(free.speed.max(), rel=0.02)  # the crossing: no turn
    assert capped.min_time > 1.05 * free.min_time
    # within a budget the cap holds; past it the cap is raised until the plan fits
    assert (
        profile_within(eight, replace(fast, course_rate=0.8), free.min_time, 2.0).min_time == capped.min_time
    )
    tight = profile_within(eight, replace(fast, course_rate=0.8), free.min_time, 1.05)
    assert free.min_time <= tight.min_time <= 1.05 * free.min_time
    with pytest.raises(ValueError, match="course_rate must be positive"):
        replace(fast, course_rate=0.0)


def test_followers_on_carpet_slow_the_turns_for_the_odometry_not_on_wood() -> None:
    from omnibot.control.followers.base import PLAN_TIME_BUDGET, make_follower
    from omnibot.control.paths.generator import figure_eight_path
    from omnibot.control.reach import floor_course_rate
    from omnibot.navigation.session import follower_limits

    assert floor_course_rate("carpet") == pytest.approx(1.635, abs=0.01)
    assert floor_course_rate("wood") > 5.0
    robot = load_robot("omni4")
    # a tight eight (turning at up to 1.9 rad/s uncapped: a 10 m eight of radius 0.4 turns at 1.4, within
    # carpet's cap); the cap holds it to 1.6 at 1.19x the minimum time, within the plan's budget
    eight = figure_eight_path(2, length=5.0, radius_min=0.3, heading="tangent")
    carpet = follower_limits(robot, 1.0, "carpet")
    assert carpet.course_rate == pytest.approx(floor_course_rate("carpet"))
    assert follower_limits(robot, 1.0).course_rate is None
    plan = make_follower("tracker", carpet).plan(eight)
    without = make_follower("tracker", replace_rate(carpet)).plan(eight)
    turn = np.max(plan.speed * np.abs(plan.kappa))
    assert turn < 0.9 * np.max(without.speed * np.abs(without.kappa))
    assert plan.min_time <= PLAN_TIME_BUDGET * min_traversal_time(eight, replace_rate(carpet)) * 1.001


def replace_rate(limits: MotionLimits) -> MotionLimits:
    """``limits`` without a course-rate cap."""
    from dataclasses import replace

    return replace(limits, course_rate=None)
