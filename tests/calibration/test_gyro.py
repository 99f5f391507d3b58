"""Gyro bias at standstill and scale from a rotation test, against the simulated MPU6050."""

from __future__ import annotations

import math

import pytest

from omnibot.calibration.gyro import GyroCalibration, calibrate_gyro, fit_scale
from omnibot.calibration.plan import Plan
from omnibot.calibration.runner import Runner
from omnibot.calibration.steps import rotation_test
from omnibot.calibration.tap import TelemetryTap, standstill_bias
from omnibot.calibration.truth import SimTruth
from omnibot.robot import RobotDescription
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
