"""The scanner's noise: normal draws by the ziggurat from uniform draws, and a revolution's
measurement with its pool of draws for the rejections."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from omnibot.sim.kernels import scan_noise
from omnibot.sim.kernels.scan_noise import _R, _ZIG_K, SCAN_POOL, normal_draw, scan_measure


@njit(cache=False)
def _normals(u: np.ndarray, pool: np.ndarray) -> tuple[np.ndarray, int]:
    """A normal draw from each of ``u``, the rejections' draws from ``pool``; and the pool draws used."""
    out = np.empty(u.shape[0])
    at = 0
    for i in range(u.shape[0]):
        out[i], at = normal_draw(u[i], pool, at, 0, pool.shape[0])
    return out, at


def _uniform_of(layer: int, negative: bool, position: int) -> float:
    """The uniform draw whose 53 bits give ``layer``, the sign and ``position`` in the layer."""
    return ((position << 9) | (int(negative) << 8) | layer) / 2.0**53


def test_the_draws_are_standard_normal() -> None:
    rng = np.random.default_rng(11)
    z, used = _normals(rng.random(1_000_000), rng.random(100_000))
    assert abs(z.mean()) < 0.005 and abs(z.std() - 1.0) < 0.003  # 5 standard errors
    assert abs(np.mean(z**4) - 3.0) < 0.025
    # the distribution: its CDF at 25 points within 0.002 of the normal's (Kolmogorov's 99.9 % bound)
    for x in np.linspace(-3.0, 3.0, 25):
        assert abs(np.mean(z <= x) - 0.5 * (1.0 + math.erf(x / math.sqrt(2.0)))) < 0.002, x
    beyond = np.mean(np.abs(z) > _R)  # the tail's draws: 2.58e-4 of them
    assert abs(beyond - math.erfc(_R / math.sqrt(2.0))) < 5e-5
    assert 0.015 < used / len(z) < 0.04  # the rejections' few pool draws


def test_a_draw_inside_its_layer_takes_no_pool_draw_and_a_rejection_takes_them_in_order() -> None:
    pool = np.array([0.5, 0.25, 0.75])
    x, at = normal_draw(_uniform_of(7, True, 5), pool, 0, 0, 3)
    assert at == 0 and x == -5 * scan_noise._ZIG_W[7]
    # the base layer past its rectangle: the tail, two pool draws a try (-log(1 - u) / R, -log(1 - u))
    x, at = normal_draw(_uniform_of(0, False, int(_ZIG_K[0]) + 1), pool, 0, 0, 3)
    xx, yy = -math.log1p(-0.5) / _R, -math.log1p(-0.25)
    assert yy + yy > xx * xx and x == _R + xx and at == 2
    # a pool of one draw read again and again
    x, at = normal_draw(_uniform_of(0, True, int(_ZIG_K[0]) + 1), pool, 0, 0, 1)
    assert x == -(_R - math.log1p(-0.5) / _R) and at == 0


def test_a_revolution_reads_its_normals_dropouts_and_pool_where_it_says() -> None:
    n = 360
    rng = np.random.default_rng(5)
    true = rng.uniform(0.5, 5.0, n)
    true[10] = np.inf
    draws = rng.random(2 * n + SCAN_POOL)
    draws[n : 2 * n] = np.maximum(draws[n : 2 * n], 0.01)
    draws[n + 20] = 0.001  # ray 20 dropped
    out = np.empty(n)
    scan_measure(true, draws, 0.0, 0.01, 0.0, 0.005, 0.15, 12.0, out)
    assert np.isfinite(np.delete(out, [10, 20])).all()
    z, _ = _normals(np.delete(draws[:n], [10, 20]), draws[2 * n :])
    assert np.isinf(out[[10, 20]]).all()
    np.testing.assert_array_equal(
        np.delete(out, [10, 20]), np.delete(true, [10, 20]) + (0.0 + 0.01 * np.delete(true, [10, 20])) * z
    )
