"""Gyro bias at standstill and scale from a rotation test, against the simulated MPU6050."""

from __future__ import annotations

import math

import pytest

from omnibot.calibration.experiments import Runner
from omnibot.calibration.gyro import GyroCalibration, Spin, calibrate_gyro, fit_scale, fit_spins
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


def _spin(
    true: float, rate: float, *, scale_error: float, bias: float, creep: float, rest: float = 3.0
) -> Spin:
    """A spin of ``true`` rad at ``rate`` rad/s that the encoders see short by ``creep`` rad/s."""
    moving = abs(true) / rate
    duration = moving + rest
    return Spin(
        gyro=(1.0 + scale_error) * true + bias * duration,
        encoders=true - math.copysign(creep * moving, true),
        duration=duration,
        moving=moving,
    )


def test_spins_at_two_rates_tell_the_floor_creep_from_the_scale() -> None:
    truth = {"scale_error": -0.009, "bias": 0.0145, "creep": 0.02}
    spins = [_spin(s * 2 * math.pi, rate, **truth) for rate in (1.0, 2.5) for s in (1.0, -1.0)]
    fit = fit_spins(3.0, 3.0 * truth["bias"], spins)
    assert fit.scale_error == pytest.approx(truth["scale_error"], abs=1e-9)
    assert fit.bias == pytest.approx(truth["bias"], abs=1e-9)
    assert fit.creep == pytest.approx(truth["creep"], abs=1e-9)
    assert fit.true_rotation(spins[0]) == pytest.approx(2 * math.pi, abs=1e-9)


def test_one_rate_reads_the_creep_as_scale() -> None:
    truth = {"scale_error": -0.009, "bias": 0.0145, "creep": 0.02}
    spins = [_spin(s * 2 * math.pi, 1.0, **truth) for s in (1.0, -1.0)]
    fit = fit_spins(3.0, 3.0 * truth["bias"], spins)
    assert fit.creep == 0.0  # cannot be told apart: not fitted
    assert fit.scale_error == pytest.approx(truth["scale_error"] + 0.02, abs=2e-3)  # ~2 % off
    without_creep = [_spin(s * 2 * math.pi, 1.0, **{**truth, "creep": 0.0}) for s in (1.0, -1.0)]
    assert fit_spins(3.0, 3.0 * truth["bias"], without_creep).scale_error == pytest.approx(-0.009, abs=1e-9)
