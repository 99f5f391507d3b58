"""PID: proportional, integral, anti-windup, filtered derivative on the measurement."""

from __future__ import annotations

import pytest

from omnibot.control.pid import PID


def test_proportional_and_integral() -> None:
    pid = PID(2.0, 1.0)
    assert pid.update(1.0, 0.1) == pytest.approx(2.0 + 0.1)
    assert pid.update(1.0, 0.1) == pytest.approx(2.0 + 0.2)


def test_integral_holds_while_clamped_and_recovers() -> None:
    pid = PID(1.0, 10.0, lo=-1.0, hi=1.0)
    for _ in range(100):
        assert pid.update(5.0, 0.01) == 1.0  # saturated: the integral must not wind up
    assert pid.integral < 0.1
    out = pid.update(-0.5, 0.01)  # the error reverses: the output leaves the limit at once
    assert out < 0.0


def test_integral_limit() -> None:
    pid = PID(0.0, 1.0, i_limit=0.5)
    for _ in range(100):
        pid.update(1.0, 0.1)
    assert pid.integral == pytest.approx(0.5)
    assert pid.output == pytest.approx(0.5)


def test_derivative_on_measurement_has_no_setpoint_kick_and_is_filtered() -> None:
    raw, filtered = PID(0.0, 0.0, 1.0), PID(0.0, 0.0, 1.0, d_tau=0.1)
    for pid in (raw, filtered):
        pid.update(0.0, 0.01, measurement=0.0)
    # a setpoint step (error jumps) with a still measurement: no derivative kick
    assert raw.update(10.0, 0.01, measurement=0.0) == 0.0
    # the measurement moves by one step: the raw derivative spikes, the filtered one a tenth of it
    spike = raw.update(0.0, 0.01, measurement=0.01)
    soft = filtered.update(0.0, 0.01, measurement=0.01)
    assert spike == pytest.approx(-1.0)
    assert soft == pytest.approx(-1.0 * 0.01 / 0.11)


def test_reset_and_bad_settings() -> None:
    pid = PID(1.0, 1.0)
    pid.update(1.0, 1.0)
    pid.reset()
    assert (pid.integral, pid.output) == (0.0, 0.0)
    assert pid.update(1.0, 0.0) == 0.0  # no time passed: output unchanged
    with pytest.raises(ValueError, match="empty"):
        PID(1.0, lo=1.0, hi=0.0)
