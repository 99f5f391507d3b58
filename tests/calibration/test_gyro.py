"""Gyro bias at standstill and scale from a rotation test, against the simulated MPU6050."""

from __future__ import annotations

import math

import pytest

from omnibot.calibration.experiments import Runner
from omnibot.calibration.gyro import GyroCalibration, Spin, Standstill, calibrate_gyro, fit_scale, fit_spins
from omnibot.calibration.plan import Plan
from omnibot.calibration.session import rotation_test
from omnibot.calibration.tap import TelemetryTap, standstill_bias
from omnibot.calibration.truth import SimTruth
from omnibot.robot.description import RobotDescription
from tests.calibration.conftest import sim_client


def test_bias_and_scale(omni4: RobotDescription) -> None:
    with sim_client(omni4, "wood", seed=11) as client:
        gyro = client.link.device.sim.gyro  # type: ignore[attr-defined]
        tap = TelemetryTap(client, omni4)
        tap.start()
        bias = standstill_bias(tap, 3.0)
        assert bias is not None
        mean, sigma, n = bias
        assert n >= 100 and 0 < sigma < 1e-3
        assert mean == pytest.approx(gyro.bias, abs=4 * sigma + 2e-4)  # 2e-4: the bias walks meanwhile
        runner = Runner(client, omni4, SimTruth(client.link.device.sim), tap, settle=0.3)  # type: ignore[attr-defined]
        runs = rotation_test(runner, Plan(rotation_turns=1.0))
        cal = calibrate_gyro(bias, runs)
        assert cal.rotations == 2
        # the simulated gyro reads (1 + e) x the true rate: the scale that undoes it is 1 / (1 + e)
        assert cal.scale == pytest.approx(1.0 / (1.0 + gyro.scale_error), abs=2e-3)
        assert cal.correct(mean + 1.0) == pytest.approx(cal.scale)
        runner.close()
        tap.stop()


def test_scale_needs_known_angles() -> None:
    assert fit_scale([], 0.0) == (None, 0)
    assert GyroCalibration(bias=0.01, bias_std=0.0, samples=1, scale=None).correct(0.51) == pytest.approx(0.5)
    assert math.isfinite(GyroCalibration(0.0, 0.0, 1, 1.02).correct(1.0))


REST = 3.0
"""s of standstill before and after every spin."""


def _manoeuvre(
    turns: list[tuple[float, float]],
    *,
    scale_error: float,
    bias: float,
    creep: float,
    walk: float = 0.0,
    encoder_error: float = 0.0,
) -> tuple[list[Standstill], list[Spin], float]:
    """Spins of ``(true rad, rate rad/s)`` from rest to rest with a standstill before and after each,
    the encoders short by ``creep`` rad/s while they turn and off by ``encoder_error`` rad per spin, the
    gyro's bias walking ``walk`` rad/s per second; the standstills, the spins and the true rotation."""
    standstills, spins = [], []
    t = 0.0

    def still() -> None:
        nonlocal t
        standstills.append(
            Standstill(gyro=(bias + walk * (t + REST / 2)) * REST, duration=REST, time=t + REST / 2)
        )
        t += REST

    still()
    for true, rate in turns:
        moving = abs(true) / rate
        mean_bias = bias + walk * (t + moving / 2)
        spins.append(
            Spin(
                gyro=(1.0 + scale_error) * true + mean_bias * moving,
                encoders=true - math.copysign(creep * moving, true) + encoder_error,
                duration=moving,
                moving=moving,
                time=t + moving / 2,
            )
        )
        t += moving
        still()
    return standstills, spins, sum(true for true, _ in turns)


TWO_RATES = [(s * 2 * math.pi, rate) for rate in (1.0, 2.5) for s in (1.0, -1.0)]


def test_spins_at_two_rates_tell_the_floor_creep_from_the_scale() -> None:
    truth = {"scale_error": -0.009, "bias": 0.0145, "creep": 0.02}
    standstills, spins, turned = _manoeuvre(TWO_RATES, **truth, walk=2e-6)
    fit = fit_spins(standstills, spins)
    assert fit.scale_error == pytest.approx(truth["scale_error"], abs=1e-9)
    assert fit.bias == pytest.approx(standstills[-1].bias, abs=1e-12)
    assert fit.creep == pytest.approx(truth["creep"], abs=1e-9)
    assert fit.true_rotation(spins[0]) == pytest.approx(2 * math.pi, abs=1e-9)
    assert fit.turned == pytest.approx(turned, abs=1e-9)


def test_an_encoder_error_does_not_turn_the_heading() -> None:
    # omni4 on carpet: the encoders miss 0.8 mrad of each spin; the bias from the standstills alone
    # keeps that out of the bias and the body's rotation (fitted with the bias, it left 0.18 degree)
    truth = {"scale_error": -0.009, "bias": 0.0145, "creep": 0.0}
    standstills, spins, turned = _manoeuvre(TWO_RATES, **truth, encoder_error=-8e-4)
    fit = fit_spins(standstills, spins)
    assert fit.bias == pytest.approx(truth["bias"], abs=1e-12)
    assert fit.turned == pytest.approx(turned, abs=1e-12)
    assert fit.scale_error == pytest.approx(truth["scale_error"], abs=2e-4)


def test_one_rate_reads_the_creep_as_scale() -> None:
    truth = {"scale_error": -0.009, "bias": 0.0145, "creep": 0.02}
    one_rate = [(s * 2 * math.pi, 1.0) for s in (1.0, -1.0)]
    fit = fit_spins(*_manoeuvre(one_rate, **truth)[:2])
    assert fit.creep == 0.0  # cannot be told apart: not fitted
    assert fit.scale_error == pytest.approx(truth["scale_error"] + 0.02, abs=2e-3)  # ~2 % off
    without_creep = fit_spins(*_manoeuvre(one_rate, **{**truth, "creep": 0.0})[:2])
    assert without_creep.scale_error == pytest.approx(-0.009, abs=1e-9)


def test_spins_need_a_standstill_on_either_side() -> None:
    standstills, spins, _ = _manoeuvre(TWO_RATES, scale_error=0.0, bias=0.0, creep=0.0)
    with pytest.raises(ValueError, match="4 spins need 5 standstills, not 4"):
        fit_spins(standstills[:-1], spins)
    with pytest.raises(ValueError, match="needs spins"):
        fit_spins(standstills[:1], [])
