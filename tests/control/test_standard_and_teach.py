"""Standard test paths and the teach recorder."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.control.paths import PathRecorder, random_path, standard_names, standard_path
from omnibot.errors import ConfigError

LENGTHS = {
    "line": 2.0,
    "circle": math.pi,
    "figure_eight": 2 * math.pi,
    "s_curve": math.pi,
    "square": 4.0,
    "lemniscate": 5.244,  # Bernoulli's lemniscate of half-width a: about 5.244 a
}


@pytest.mark.parametrize("name", standard_names())
def test_every_standard_path_starts_at_the_origin_along_x(name: str) -> None:
    path = standard_path(name, size=1.0, spacing=0.01)
    assert path.start == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)
    assert path.length == pytest.approx(LENGTHS[name], rel=2e-3)
    assert np.diff(path.s).max() <= 0.01 + 1e-9
    dx, dy = path.x[1] - path.x[0], path.y[1] - path.y[0]
    assert math.atan2(dy, dx) == pytest.approx(0.0, abs=0.02)
    assert np.all(path.theta == 0.0)
    tangent = standard_path(name, size=1.0, heading="tangent")
    assert tangent.theta[0] == pytest.approx(0.0, abs=0.02)


def test_closed_paths_close_and_tangent_heading_turns() -> None:
    for name in ("circle", "figure_eight", "square", "lemniscate"):
        p = standard_path(name)
        assert math.hypot(p.x[-1], p.y[-1]) < 1e-6
    assert standard_path("circle", heading="tangent").theta[-1] == pytest.approx(2 * math.pi, abs=0.02)
    assert standard_path("figure_eight", heading="tangent").theta[-1] == pytest.approx(0.0, abs=0.02)


def test_bad_names_and_sizes() -> None:
    with pytest.raises(ConfigError, match="did you mean 'circle'"):
        standard_path("circel")
    with pytest.raises(ConfigError, match="heading"):
        standard_path("line", heading="sideways")
    with pytest.raises(ConfigError, match="positive"):
        standard_path("line", size=0.0)


def test_random_path_is_smooth_long_and_reproducible() -> None:
    a, b = random_path(20.0, seed=3), random_path(20.0, seed=3)
    assert a.length >= 20.0 and np.array_equal(a.x, b.x)
    assert np.max(np.abs(np.diff(a.theta))) < 0.1
    assert not np.array_equal(a.x, random_path(20.0, seed=4).x)


def test_recorder_by_distance_keeps_turns_and_speed() -> None:
    rec = PathRecorder("distance", 0.1, store_speed=True)
    for k in range(101):  # 1 m at 0.5 m/s along x, poses every 10 ms
        rec.add(0.02 * k, 0.01 * k, 0.0, 0.0)
    for k in range(1, 21):  # then a turn in place of 1 rad
        rec.add(2.0 + 0.05 * k, 1.0, 0.0, 0.05 * k)
    path = rec.path()
    assert np.diff(path.s[:11]) == pytest.approx(np.full(10, 0.1))
    assert path.v is not None and path.v[5] == pytest.approx(0.5)
    assert path.theta[-1] == pytest.approx(1.0) and np.sum(path.x == 1.0) >= 3
    assert path.t is not None and path.t[0] == 0.0


def test_recorder_by_time_and_fixed_heading() -> None:
    rec = PathRecorder("time", 0.5, store_heading=False)
    for k in range(0, 301):
        rec.add(0.01 * k, 0.001 * k, 0.0, 0.3 + 0.001 * k)
    path = rec.path()
    assert path.t is not None and np.diff(path.t) == pytest.approx(np.full(len(path) - 1, 0.5))
    assert np.all(path.theta == pytest.approx(0.3)) and path.v is None
    with pytest.raises(ValueError, match="two"):
        PathRecorder().path()
    with pytest.raises(ValueError, match="sampling"):
        PathRecorder("space")
