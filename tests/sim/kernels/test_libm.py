"""The batch kernel's own tanh, sin and cos: within an ulp or three of the C library's."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.sim.kernels import libm


def _ulps(got: np.ndarray, want: np.ndarray) -> np.ndarray:
    return np.asarray(np.abs(got - want) / np.spacing(np.abs(want)))


@pytest.mark.parametrize("scale", [1e-6, 0.3, 1.0, 4.0, 30.0])
def test_tanh_is_within_three_ulps_of_the_c_library(scale: float) -> None:
    x = np.random.default_rng(1).uniform(-scale, scale, 3000)
    got = np.array([libm.tanh(v) for v in x])
    assert _ulps(got, np.array([math.tanh(v) for v in x])).max() <= 3.0
    assert libm.tanh(100.0) == 1.0 and libm.tanh(-1e300) == -1.0
    assert math.copysign(1.0, libm.tanh(-0.0)) == -1.0 and libm.tanh(0.0) == 0.0


@pytest.mark.parametrize("scale", [1e-3, 1.0, 100.0, libm.REDUCE_LIMIT])
def test_sin_and_cos_are_within_an_ulp_of_the_c_library(scale: float) -> None:
    x = np.random.default_rng(2).uniform(-scale, scale, 3000)
    sin, cos = np.array([libm.sincos(v) for v in x]).T
    assert _ulps(sin, np.sin(x)).max() <= 1.0 and _ulps(cos, np.cos(x)).max() <= 1.0
    assert np.array_equal([libm.cos(v) for v in x], cos)
