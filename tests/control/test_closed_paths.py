"""The seeded figure eights and closed free-form curves: deterministic per seed, closed, smooth
(continuous curvature, across the join too), within their radius of curvature, not self-crossing."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from omnibot.control.paths import MotionLimits, Path, curvature, time_optimal_profile
from omnibot.control.paths.generator import closed_curve_path, figure_eight_path
from omnibot.errors import ConfigError
from omnibot.robot import load_robot

Generator = Callable[..., Path]
CASES = [(figure_eight_path, 10.0), (closed_curve_path, 6.0)]
SEEDS = range(1, 9)


def _loop_curvature(path: Path) -> np.ndarray:
    """Curvature at every point of a closed path, the join included (first point = last)."""
    x, y = path.x[:-1], path.y[:-1]
    dx, dy = np.roll(x, -1) - x, np.roll(y, -1) - y
    direction = np.arctan2(dy, dx)
    turn = (direction - np.roll(direction, 1) + math.pi) % (2 * math.pi) - math.pi
    return turn / np.hypot(dx, dy)


@pytest.mark.parametrize(("make", "length"), CASES)
def test_the_same_seed_gives_the_same_path_and_another_seed_another(make: Generator, length: float) -> None:
    a, b = make(5, length=length), make(5, length=length)
    for col in ("x", "y", "theta"):
        assert np.array_equal(getattr(a, col), getattr(b, col))
    others = [make(seed, length=length) for seed in (6, 7)]
    assert not all(np.allclose(a.y, c.y) for c in others)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize(("make", "length"), CASES)
def test_closed_smooth_and_within_the_radius(make: Generator, length: float, seed: int) -> None:
    radius, step = 0.4, 0.01
    path = make(seed, length=length, radius_min=radius, spacing=step)
    assert path.start == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    assert path.end[:2] == pytest.approx((0.0, 0.0), abs=1e-12)
    assert math.remainder(path.end[2], 2 * math.pi) == pytest.approx(0.0, abs=1e-9)  # the heading too
    assert math.atan2(path.y[1], path.x[1]) == pytest.approx(0.0, abs=step / radius)
    assert path.length == pytest.approx(length, rel=1e-4)
    kappa = _loop_curvature(path)
    assert np.abs(kappa).max() <= 1.0 / radius * 1.02
    # continuous curvature, across the join as well: its change between samples is small
    assert np.abs(np.diff(np.concatenate((kappa, kappa[:1])))).max() <= 0.2 / radius
    assert np.abs(curvature(path)[1:-1]).max() <= 1.0 / radius * 1.02


@pytest.mark.parametrize("seed", SEEDS)
def test_a_closed_curve_does_not_cross_itself_and_an_eight_crosses_once(seed: int) -> None:
    closed = closed_curve_path(seed, length=6.0, radius_min=0.4)
    # star-shaped around the centroid: the angle seen from it only ever turns one way, once round
    cx, cy = closed.x[:-1].mean(), closed.y[:-1].mean()
    angle = np.unwrap(np.arctan2(closed.y - cy, closed.x - cx))
    steps = np.diff(angle)
    assert np.all(steps > 0) or np.all(steps < 0)
    assert abs(angle[-1] - angle[0]) == pytest.approx(2 * math.pi, abs=1e-6)
    eight = figure_eight_path(seed, length=10.0, radius_min=0.4)
    # the direction of travel turns one way round a lobe and back the other: no net turn
    direction = np.unwrap(np.arctan2(np.diff(eight.y), np.diff(eight.x)))
    assert abs(direction[-1] - direction[0]) < 0.1
    assert np.ptp(direction) > math.pi  # a lobe: more than a half turn one way


def test_heading_modes_fixed_tangent_swing_and_random() -> None:
    assert np.all(figure_eight_path(1, heading="fixed").theta == 0.0)
    tangent = closed_curve_path(1, heading="tangent")
    direction = np.unwrap(np.arctan2(np.diff(tangent.y), np.diff(tangent.x)))
    assert np.abs(0.5 * (tangent.theta[1:-2] + tangent.theta[2:-1]) - direction[1:-1]).max() < 2e-3
    swing = figure_eight_path(1, heading="swing", swing=1.0, swing_rate=1.5)
    assert 0.1 < np.abs(swing.theta).max() <= 1.0 + 1e-9
    assert np.abs(np.diff(swing.theta)).max() <= 1.5 * 0.01 * 1.001
    modes = {
        "fixed" if np.all(p.theta == 0) else "moving"
        for p in (make(seed) for make in (figure_eight_path, closed_curve_path) for seed in SEEDS)
    }
    assert modes == {"fixed", "moving"}  # the seed picks the heading mode


@pytest.mark.parametrize("preset", ["omni4", "omni3", "mecanum4"])
def test_profiled_within_the_robots_lateral_limit(preset: str) -> None:
    limits = MotionLimits.from_robot(load_robot(preset))
    for make, length in CASES:
        prof = time_optimal_profile(make(2, length=length), limits)
        assert np.max(prof.speed**2 * np.abs(prof.kappa)) <= limits.lateral * 1.02
        assert prof.min_time > length / limits.v_max


@pytest.mark.parametrize(
    ("make", "options", "message"),
    [
        (figure_eight_path, {"length": 6.0, "radius_min": 0.4}, "figure eight of 6 m cannot keep"),
        (closed_curve_path, {"length": 2.0, "radius_min": 0.4}, "cannot keep a radius"),
        (closed_curve_path, {"harmonics": 0}, "harmonics must be at least 1"),
        (figure_eight_path, {"heading": "sideways"}, "unknown heading mode 'sideways'"),
        (closed_curve_path, {"spacing": -1.0}, "spacing must be a positive number"),
        (figure_eight_path, {"swing": math.nan}, "swing must be a non-negative number"),
    ],
)
def test_bad_arguments_are_refused(make: Generator, options: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        make(1, **options)
