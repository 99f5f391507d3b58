"""Heading filter: bias at standstill and while driving straight, scale while turning, slips ignored."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.estimation.heading import HeadingFilter, HeadingFilterConfig

DT = 0.01


def run(flt: HeadingFilter, seconds: float, rate: float, bias: float, scale: float, **kw: object) -> float:
    """Feed a gyro with ``bias``/``scale`` and perfect encoders for a body turning at ``rate``."""
    theta = 0.0
    for _ in range(round(seconds / DT)):
        true = rate * DT
        flt.update(DT, (1 + scale) * true + bias * DT, true, **kw)  # type: ignore[arg-type]
        theta += true
    return theta


def test_bias_is_learned_at_standstill_and_the_heading_holds() -> None:
    flt = HeadingFilter()
    run(flt, 2.0, 0.0, bias=0.012, scale=0.0, standstill=True)
    assert flt.bias == pytest.approx(0.012, abs=2e-4)
    assert flt.theta == 0.0  # standing still: no drift at all


def test_bias_is_learned_while_driving_straight() -> None:
    flt = HeadingFilter()
    run(flt, 20.0, 0.0, bias=-0.008, scale=0.0)
    assert flt.bias == pytest.approx(-0.008, abs=5e-4)
    assert abs(flt.theta) < 0.01  # a raw gyro sum would be off by 0.16 rad


def test_scale_is_learned_while_turning_steadily() -> None:
    flt = HeadingFilter()
    run(flt, 1.0, 0.0, bias=0.005, scale=0.015, standstill=True)
    truth = run(flt, 2 * 2 * math.pi, 1.0, bias=0.005, scale=0.015)
    assert flt.scale == pytest.approx(0.015, abs=2e-3)
    assert flt.theta == pytest.approx(truth, abs=0.01)


def test_a_slip_of_the_wheels_does_not_enter_the_heading() -> None:
    flt = HeadingFilter()
    run(flt, 1.0, 0.0, bias=0.0, scale=0.0, standstill=True)
    for k in range(100):  # the wheels report a 0.3 rad spin the body (and gyro) never made
        flt.update(DT, 0.0, 0.003 if k < 100 else 0.0)
    assert flt.slipping
    assert abs(flt.theta) < 0.01
    run(flt, 2.0, 0.0, bias=0.0, scale=0.0)
    assert abs(flt.theta) < 0.01 and not flt.slipping


def test_outside_slip_flag_and_saturated_gyro() -> None:
    flt = HeadingFilter(HeadingFilterConfig(gyro_range=4.0))
    flt.update(DT, 0.01, 0.5, slip=True)  # flagged: the encoders' 0.5 rad is ignored
    assert flt.theta == pytest.approx(0.01) and flt.slipping
    sat = HeadingFilter(HeadingFilterConfig(gyro_range=4.0))
    inc = sat.update(DT, 0.04, 0.06)  # the gyro is pinned at its range: the wheels say 6 rad/s
    assert inc == pytest.approx(0.06)
    theta = 0.06
    for _ in range(49):  # a spin past the range on wheels that agree: they carry it throughout
        theta += sat.update(DT, 0.04, 0.06)
    assert theta == pytest.approx(0.06 * 50)


def test_a_clipped_gyro_is_the_least_the_body_turned() -> None:
    """A body spinning past the gyro's range usually has a wheel skidding: wheels that read less
    than the clipped gyro, or are flagged as slipping, must not replace it (omni3 at top speed)."""
    flagged = HeadingFilter(HeadingFilterConfig(gyro_range=4.0))
    assert flagged.update(DT, 0.04, 0.06, slip=True) == pytest.approx(0.04)  # skidding: the clip holds
    slower = HeadingFilter(HeadingFilterConfig(gyro_range=4.0))
    before = slower.P[0, 0]
    assert slower.update(DT, 0.04, 0.02) == pytest.approx(0.04)  # less than the clip: cannot be
    assert slower.P[0, 0] > before + (0.04 * 0.05) ** 2 * 0.9  # what the clip hides widens the heading
    reverse = HeadingFilter(HeadingFilterConfig(gyro_range=4.0))
    assert reverse.update(DT, -0.04, 0.06) == pytest.approx(-0.04)  # the other way: not the body's
    spun = HeadingFilter(HeadingFilterConfig(gyro_range=4.0))
    theta = 0.0
    for k in range(20):  # 0.2 s at 4.1 rad/s, wheels reading 2 rad/s and flagged after the first
        theta += 0.041
        spun.update(DT, 0.04, 0.02, slip=k > 0)
    assert spun.theta == pytest.approx(theta, abs=0.03)  # the encoders' bridge: 0.4 rad short


def test_reset_heading_keeps_the_learned_gyro() -> None:
    flt = HeadingFilter()
    run(flt, 2.0, 0.0, bias=0.01, scale=0.0, standstill=True)
    flt.reset_heading(1.5)
    assert flt.theta == 1.5 and flt.bias == pytest.approx(0.01, abs=2e-4)
    assert np.all(np.isfinite(flt.P))


def test_fast_wheels_creeping_in_rotation_count_for_less() -> None:
    # omni3 at 4 m/s on carpet: the driven wheels creep 4e-4 rad/s in rotation with no skid to see
    # (the body drives straight, the gyro calibrated): at speed their rotation weighs less
    def drift(speed: float) -> float:
        flt = HeadingFilter()
        flt.calibrated(0.0, 0.0, bias_std=5e-5, scale_std=5e-4)
        for _ in range(round(11.0 / DT)):
            flt.update(DT, 0.0, 4e-4 * DT, speed=speed)
        return flt.theta

    slow, fast = drift(0.0), drift(4.0)
    assert slow > 3e-4  # trusted, the wheels' 4.4 mrad of creep pull the heading 0.4 mrad
    assert fast < 0.1 * slow


def test_a_standstill_keeps_the_bias_it_measured_against_the_wheels_creep() -> None:
    """omni3 on the long corridor: a 3 s standstill measures the bias to ~5e-5 rad/s (its mean rate;
    the TEL heading's 0.01 degree steps telescope over it), and driving away the wheels creep 2e-4
    rad/s in rotation below the slip check. Taken one sample at a time (each step as new white
    noise) the bias was left 4.7e-4 rad/s uncertain, the creep became bias and the heading followed
    the wheels (3.6 mrad in 20 s; 0.56 degree mean on the route with a constant bias)."""
    rng = np.random.default_rng(3)
    step = math.radians(0.01)
    bias, creep = 0.012, 2e-4
    flt = HeadingFilter()
    psi = 0.0
    for k in range(round(23.0 / DT)):
        standing = k < round(3.0 / DT)
        sent = round(psi / step) * step
        psi += bias * DT + 8.7e-5 * math.sqrt(DT) * rng.standard_normal()
        flt.update(DT, round(psi / step) * step - sent, None if standing else creep * DT, standstill=standing)
        if k == round(3.0 / DT) - 1:
            assert flt.bias == pytest.approx(bias, abs=1e-4)  # the standstill's mean rate
            assert math.sqrt(flt.P[1, 1]) < 1e-4  # and as known as that: 8.7e-5 / sqrt(3 s) and the steps
    assert flt.bias == pytest.approx(bias, abs=5e-5)
    assert abs(flt.theta) < 1.5e-3  # the wheels alone say 4 mrad


def test_a_calibration_during_a_standstill_is_kept() -> None:
    flt = HeadingFilter()
    run(flt, 1.0, 0.0, bias=0.01, scale=0.0, standstill=True)
    flt.calibrated(0.002, 0.003, bias_std=5e-5, scale_std=5e-4)
    run(flt, 0.5, 0.0, bias=0.002, scale=0.0, standstill=True)  # still standing: from the calibration on
    assert flt.bias == pytest.approx(0.002, abs=1e-4) and flt.scale == pytest.approx(0.003)
