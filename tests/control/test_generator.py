"""The seeded smooth random path generator: deterministic per seed, smooth, within its bounds and
the robot's limits once profiled."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.control.paths import MotionLimits, curvature, smooth_random_path, time_optimal_profile
from omnibot.errors import ConfigError
from omnibot.robot import load_robot

SEEDS = range(1, 9)


def test_the_same_seed_gives_the_same_path_and_another_seed_another() -> None:
    a, b = smooth_random_path(7, length=3.0), smooth_random_path(7, length=3.0)
    for col in ("x", "y", "theta"):
        assert np.array_equal(getattr(a, col), getattr(b, col))
    c = smooth_random_path(8, length=3.0)
    assert not np.allclose(a.y, c.y)
    assert not np.allclose(a.theta, c.theta)


@pytest.mark.parametrize("seed", SEEDS)
def test_starts_at_the_origin_along_x_with_the_asked_length(seed: int) -> None:
    path = smooth_random_path(seed, length=4.0, spacing=0.01)
    assert path.start == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    assert math.atan2(path.y[1], path.x[1]) == pytest.approx(0.0, abs=0.01 / 0.5)
    assert path.length == pytest.approx(4.0, rel=1e-6)
    assert np.diff(path.s).max() == pytest.approx(0.01, rel=1e-6)


@pytest.mark.parametrize("seed", SEEDS)
def test_smooth_within_the_curvature_and_swing_bounds(seed: int) -> None:
    radius, swing, rate, step = 0.5, 1.0, 1.5, 0.01
    path = smooth_random_path(seed, length=6.0, radius_min=radius, swing=swing, swing_rate=rate, spacing=step)
    kappa = curvature(path)
    assert np.abs(kappa[1:-1]).max() <= 1.0 / radius * 1.01
    # the direction turns by at most step / radius between samples, and the curvature itself is
    # continuous: its change between samples is a small fraction of its bound
    direction = np.unwrap(np.arctan2(np.diff(path.y), np.diff(path.x)))
    assert np.abs(np.diff(direction)).max() <= step / radius * 1.01
    assert np.abs(np.diff(kappa[1:-1])).max() <= 0.05 / radius
    assert np.abs(path.theta).max() <= swing + 1e-9
    assert np.abs(np.diff(path.theta)).max() <= rate * step * 1.001
    # the heading rate is continuous too (no kinks): second differences of order step^2
    assert np.abs(np.diff(path.theta, 2)).max() <= 10.0 * rate * step * step / radius
    assert np.ptp(path.theta) > 0.1  # it does swing


def test_tangent_heading_faces_the_direction_of_travel_and_fixed_holds_it() -> None:
    path = smooth_random_path(3, length=4.0, heading="tangent")
    direction = np.unwrap(np.arctan2(np.diff(path.y), np.diff(path.x)))
    assert np.abs(0.5 * (path.theta[1:] + path.theta[:-1]) - direction).max() < 1e-3
    assert np.all(smooth_random_path(3, length=4.0, heading="fixed").theta == 0.0)


@pytest.mark.parametrize("preset", ["omni4", "omni3", "mecanum4"])
def test_profiled_paths_stay_within_the_robots_limits(preset: str) -> None:
    robot = load_robot(preset)
    limits = MotionLimits.from_robot(robot)
    radius = 1.0 / robot.limits.curvature_max
    for seed in range(1, 4):
        path = smooth_random_path(seed, length=3.0, radius_min=max(radius, 0.3))
        prof = time_optimal_profile(path, limits)
        speed = prof.speed
        assert speed.max() <= limits.v_max * (1 + 1e-9)
        assert np.abs(prof.u * prof.rt).max() <= limits.w_max * (1 + 1e-9)
        assert np.max(speed**2 * np.abs(prof.kappa)) <= limits.lateral * 1.02
        assert prof.min_time > path.length / limits.v_max


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"heading": "sideways"}, "unknown heading mode 'sideways'"),
        ({"length": -1.0}, "length must be a positive number"),
        ({"radius_min": 0.0}, "radius_min must be a positive number"),
        ({"swing": math.nan}, "swing must be a non-negative number"),
        ({"wavelength": -2.0}, "wavelength must be a positive number"),
        ({"length": 1e6}, "too long"),
    ],
)
def test_bad_arguments_are_refused_with_one_clear_line(options: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        smooth_random_path(1, **options)  # type: ignore[arg-type]
