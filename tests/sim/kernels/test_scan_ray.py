"""Where the scanner's rays point: the table of their angles, and the heading turned by a series."""

from __future__ import annotations

import math

import numpy as np

from omnibot.sim.kernels.scan_ray import RAY_A, RAY_COS, RAY_SIN, RAY_T, SMALL_TURN, ray_table, turned


def test_a_turn_by_the_series_is_the_c_librarys_cos_and_sin_within_a_few_ulp() -> None:
    rng = np.random.default_rng(2)
    for a, d in zip(rng.uniform(-7.0, 7.0, 2000), rng.uniform(-SMALL_TURN, SMALL_TURN, 2000), strict=True):
        c, s = turned(math.cos(a), math.sin(a), d)
        assert abs(c - math.cos(a + d)) < 1e-15 and abs(s - math.sin(a + d)) < 1e-15, (a, d)


def test_the_ray_table_holds_each_rays_time_angle_cos_and_sin() -> None:
    t, a = np.linspace(0.0, 0.1, 7), np.linspace(0.0, -6.0, 7)
    rays = ray_table(t, a)
    np.testing.assert_array_equal(rays[:, RAY_T], t)
    np.testing.assert_array_equal(rays[:, RAY_A], a)
    assert list(rays[:, RAY_COS]) == [math.cos(x) for x in a] and list(rays[:, RAY_SIN]) == [
        math.sin(x) for x in a
    ]
