"""The scanner's measurement: a revolution's true ranges, its normal and uniform draws, and what it
reports."""

from __future__ import annotations

import numpy as np

from omnibot.sim.kernels.scan_noise import scan_measure


def test_a_revolution_reads_its_normals_and_dropouts_ray_by_ray() -> None:
    n = 360
    rng = np.random.default_rng(5)
    true = rng.uniform(0.5, 5.0, n)
    true[10] = np.inf  # no return
    true[30] = 11.99  # its noise takes it past range_max
    normals, uniforms = rng.standard_normal(n), np.maximum(rng.random(n), 0.01)
    normals[30], uniforms[20] = 1.0, 0.001  # ray 20 dropped
    out = np.empty(n)
    scan_measure(true, normals, uniforms, 0.002, 0.01, 0.0, 0.005, 0.15, 12.0, out)
    kept = np.delete(np.arange(n), [10, 20, 30])
    assert np.isinf(out[[10, 20, 30]]).all()
    np.testing.assert_array_equal(out[kept], true[kept] + (0.002 + 0.01 * true[kept]) * normals[kept])


def test_a_measured_range_is_quantised_to_the_resolution_and_kept_within_the_limits() -> None:
    true = np.array([1.0, 0.2, 0.1])
    normals, uniforms = np.array([0.3, -0.1, 0.0]), np.full(3, 0.5)
    out = np.empty(3)
    scan_measure(true, normals, uniforms, 0.0, 0.01, 0.00025, 0.0, 0.15, 12.0, out)
    # 1.003 is 4012 quarter millimetres, 0.1998 rounds to 799 of them; 0.1 lies below range_min
    assert out[0] == round(1.003 / 0.00025) * 0.00025
    assert out[1] == round(0.1998 / 0.00025) * 0.00025
    assert np.isinf(out[2])
