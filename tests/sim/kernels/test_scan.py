"""The laser scanner's kernels: the pose log the step writes, and a revolution in one call against
the cast and the measurement it is made of."""

from __future__ import annotations

import math

import numpy as np

from omnibot.sim import kernels
from omnibot.sim.kernels import layout
from omnibot.sim.kernels.scan import (
    P_AX,
    P_AY,
    P_DROPOUT,
    P_DT,
    P_INNER,
    P_NOISE_FRACTION,
    P_RANGE_MAX,
    P_RANGE_MIN,
    P_REACH,
    P_RESOLUTION,
    SCAN_PARAMS,
)
from omnibot.sim.world import load_world


def log_state(capacity: int, stride_us: int, dt_us: int) -> tuple[np.ndarray, np.ndarray]:
    """A simulator's float and int state holding nothing but a pose log, on, recording from 0."""
    si = np.zeros(layout.I_HEADER, dtype=np.int64)
    si[layout.I_LOG_CAP], si[layout.I_LOG_ON] = capacity, 1
    si[layout.I_LOG_NEXT], si[layout.I_LOG_STRIDE], si[layout.I_LOG_DT] = stride_us, stride_us, dt_us
    offsets = kernels.sim_offsets.py_func(si)
    return np.zeros(offsets[5]), np.resize(si, offsets[-1])


def test_the_pose_log_keeps_the_pose_of_every_stride_says_when_to_flush_and_counts_what_overflows() -> None:
    sf, si = log_state(capacity=3, stride_us=5000, dt_us=1000)
    si[layout.I_LOG_FLUSH] = 10000
    start = kernels.sim_offsets.py_func(si)[4]
    said = {}
    for step in range(20):  # steps of 1 ms beginning at step * 1000 us, ending a ms later
        said[step + 1] = kernels.pose_log(sf, si, float(step), -float(step), 0.5 * step, step * 1000)
    # the flush is due with the records at or after 10 ms
    assert {end for end, status in said.items() if status} == {10, 15, 20}
    assert set(said.values()) == {0, layout.STEP_SCAN}
    np.testing.assert_array_equal(sf[start:].reshape(3, 3), [[4, -4, 2.0], [9, -9, 4.5], [14, -14, 7.0]])
    assert si[layout.I_LOG_N] == 4  # the fourth row (19 ms) counted, nowhere to go
    assert si[layout.I_LOG_NEXT] == 25000


def test_a_revolution_in_one_call_is_the_cast_and_the_measurement_and_asks_for_an_index_it_lacks() -> None:
    segments = np.ascontiguousarray(load_world("room").segments)
    n = 360
    offsets = np.arange(n, dtype=np.float64) * (0.1 / n)
    angles = np.arange(n, dtype=np.float64) * (-2 * math.pi / n)
    hist = np.asarray(
        np.column_stack((np.linspace(1.0, 1.3, 21), np.linspace(1.0, 1.1, 21), np.linspace(0.0, 0.6, 21))),
        dtype=np.float64,
    )
    no_v, no_off = np.zeros((0, 2)), np.zeros(1, dtype=np.int64)
    rng = np.random.default_rng(3)
    draws = (rng.standard_normal(n), rng.random(n))
    params = np.zeros(SCAN_PARAMS)
    params[[P_DT, P_REACH, P_INNER, P_NOISE_FRACTION, P_RESOLUTION, P_DROPOUT, P_RANGE_MIN, P_RANGE_MAX]] = (
        0.005, 14.0, -1.0, 0.01, 0.00025, 0.05, 0.15, 12.0,
    )  # fmt: skip
    index = kernels.scan_index(segments, 1.15, 1.05, 0.5, 14.0)
    true, measured = np.full(n, math.inf), np.full(n, -1.0)
    rays = kernels.ray_table(offsets, angles)
    args = (3.0, 0, n, rays, hist, 0, params, segments, *index, no_v, no_off, true)
    assert not kernels.scan_revolution(*args, *draws, measured)  # no index yet
    params[[P_AX, P_AY, P_INNER]] = 1.15, 1.05, 0.1  # a disc that misses the first rows
    assert not kernels.scan_revolution(*args, *draws, measured)
    assert np.isinf(true).all() and (measured == -1.0).all()  # nothing done
    params[P_INNER] = 0.5
    assert kernels.scan_revolution(*args, *draws, measured)
    expected_true, expected = np.empty(n), np.empty(n)
    kernels.scan_rays(
        3.0 + offsets,
        angles,
        0.0,
        0.005,
        hist,
        0,
        0.0,
        0.0,
        segments,
        *index,
        no_v,
        no_off,
        14.0,
        expected_true,
    )
    kernels.scan_measure(expected_true, *draws, 0.0, 0.01, 0.00025, 0.05, 0.15, 12.0, expected)
    np.testing.assert_array_equal(true, expected_true)
    np.testing.assert_array_equal(measured, expected)
    assert np.isfinite(true).all() and 0 < np.isinf(measured).sum() < 0.1 * n  # the dropouts
    # a part of a revolution, no draws: those rays cast, nothing measured
    part, nothing = np.full(n, math.inf), np.zeros(0)
    assert kernels.scan_revolution(3.0, 10, 20, *args[3:11], no_v, no_off, part, nothing, nothing, nothing)
    np.testing.assert_array_equal(part[10:20], expected_true[10:20])
    assert np.isinf(part[:10]).all() and np.isinf(part[20:]).all()
