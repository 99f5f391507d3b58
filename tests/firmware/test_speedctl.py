"""The wheel-speed loop (firmware/speedctl.py): after a step in a wheel's target, large errors
integrate less until the wheel is within the band, and what that does to the overshoot.

mecanum4 on carpet in the simulator (the MicroPython firmware in lockstep): its feedforward gives
less power than the carpet needs (135 counts on course 90 at 0.8 m/s, 140-145 held), so the integral
has work to do, and the old loop stored the lag of the rise in it too. Before this loop, on course
90 a step to 0.8 m/s went 28 % past it (benchmarks/speed_loop.py); with the rise ended within the
band, 9.7 %; ended when the wheel reaches its target, 6.8 %.
"""

from __future__ import annotations

import math

import pytest
from benchmarks.speed_loop import run

from omnibot.firmware.config import build_config
from omnibot.firmware.config_loops import SPEED_BAND_POWER
from omnibot.firmware.speedctl import STEADY_PERIODS, SpeedControl
from omnibot.robot import load_robot

CPR = 440
PWM_MAX = 255
PERIOD = 10_000


def test_mecanum4_on_carpet_stays_near_the_asked_speed_after_a_step() -> None:
    result = run("mecanum4", "carpet", 90.0, 0.8, ramp=False)
    assert result.wheel < 0.10  # was 0.28 (0.068 now)
    assert result.body < 0.10  # was 0.30 (0.065 now)
    assert result.rise < 0.6  # and still gets there (0.48 s before, 0.34 on the band's end, 0.36 now)


@pytest.mark.parametrize(("course", "before"), [(0.0, 0.09), (44.5, 0.09), (90.0, 0.08)])
def test_a_ramp_with_its_planned_acceleration_ends_near_the_asked_speed(course: float, before: float) -> None:
    """mecanum4 on carpet, 1.4 m/s^2 to 0.8 m/s: without the acceleration the integral stores the
    torque of the ramp and carries the body past the speed asked (``before``, over the speed asked:
    0.092, 0.086 and 0.076; 0.11, 0.11 and 0.10 before the held target's faster integral unlearned it
    sooner, 0.10, 0.10 and 0.09 before the integral learned against the target each period was driven
    for); with it fed forward the body ends within 2 % (issue 17), reaching 98 % of its speed within
    0.1 s of the ramp's end (0.57 s; 0.64-0.66 s measured, 0.58 without the feed-forward, which
    overshoots). It was 0.60-0.62 s while the integral also stored the staircase's lag, one VEL step
    behind every new target all the way up: on carpet that lag stood in for part of the feedforward's
    shortfall at the ramp's end, which is now learned after it."""
    old = run("mecanum4", "carpet", course, 0.8, ramp=True)
    new = run("mecanum4", "carpet", course, 0.8, ramp=True, plan=True)
    assert old.body_asked == pytest.approx(before, abs=0.01)
    assert new.body_asked < 0.03
    assert new.body_asked < old.body_asked / 4  # 0.009-0.013 against 0.088-0.098
    assert new.rise <= 0.8 / 1.4 + 0.1


def test_large_errors_integrate_less_after_a_step_only() -> None:
    band = 5.0
    sc = SpeedControl([CPR], 0.0, 1.0, PERIOD, PWM_MAX, band)
    out = [0]
    sc.reset([0])
    sc.update(PERIOD, [0], [4 * band], [0.0], out)  # a step from rest: the period was driven for rest
    assert sc._integ[0] == 0.0
    sc.update(PERIOD, [0], [4 * band], [0.0], out)  # still rising, err = 4 bands: 1/17 of the rate
    assert sc._integ[0] == pytest.approx(4 * band * 0.01 / 17)
    sc.reset([0])
    for k in range(1, 5):  # a ramp in steps smaller than the band: the plain PI, a period late
        sc.update(PERIOD, [0], [0.9 * band * k], [0.0], out)
    assert sc._integ[0] == pytest.approx(0.9 * band * 0.01 * (0 + 1 + 2 + 3))
    sc = SpeedControl([CPR], 0.0, 1.0, PERIOD, PWM_MAX)  # no band: the plain PI after a step too
    sc.reset([0])
    sc.update(PERIOD, [0], [4 * band], [0.0], out)
    sc.update(PERIOD, [0], [4 * band], [0.0], out)
    assert sc._integ[0] == pytest.approx(4 * band * 0.01)


def test_the_rise_ends_when_the_wheel_reaches_its_target() -> None:
    """After a step the integral grows at the rise's rate until the wheel's error changes sign, also
    within the band (the last band of the rise is lag too); then at the full rate, even if the wheel
    falls back. After the controller's slew (``rise``: no step's sign) the rise ends within the band."""
    band = 5.0
    sc = SpeedControl([CPR], 0.0, 1.0, PERIOD, PWM_MAX, band)
    out = [0]
    sc.reset([0])
    sc.update(PERIOD, [0], [20.0], [0.0], out)  # step: rising
    per_period = 11  # counts in 10 ms: 15.7 rad/s, within the band, below the target
    err = 20.0 - per_period * 2 * math.pi / CPR / 0.01
    assert 0.0 < err < band
    before = sc._integ[0]
    sc.update(PERIOD, [per_period], [20.0], [0.0], out)  # within the band, not there: still rising
    assert sc._integ[0] - before == pytest.approx(err * 0.01 / (1.0 + (err / band) ** 2))
    sc.update(PERIOD, [2 * per_period + 15], [20.0], [0.0], out)  # 26 counts, 37 rad/s: past it
    before = sc._integ[0]
    sc.update(PERIOD, [2 * per_period + 15], [20.0], [0.0], out)  # wheel stopped, err 20: the full rate
    assert sc._integ[0] - before == pytest.approx(20.0 * 0.01)
    sc.reset([0])
    sc.rise()  # a slew (targets in steps smaller than the band): the rise ends within the band
    sc.update(PERIOD, [0], [4.0], [0.0], out)
    before = sc._integ[0]
    sc.update(PERIOD, [0], [4.0], [0.0], out)  # not there, within the band: the full rate
    assert sc._integ[0] - before == pytest.approx(4.0 * 0.01)


def test_a_large_steady_error_is_still_integrated_away() -> None:
    """A wheel whose feedforward gives half the power it needs (P alone leaves 3 bands of error)
    still reaches its target: the band slows the integral, it does not stop it."""
    kp, ki, load = 1.93, 38.6, 7.2  # mecanum4's gains; PWM counts per rad/s the wheel needs
    sc = SpeedControl([CPR], kp, ki, PERIOD, PWM_MAX, SPEED_BAND_POWER * PWM_MAX / kp)
    out = [0]
    sc.reset([0])
    speed = angle = 0.0
    target = 24.6
    for _ in range(4000):  # 4 s in 1 ms steps, a first-order wheel (time constant 70 ms)
        sc.update(1000, [int(angle * CPR / 6.283185307179586)], [target], [0.5 * load * target], out)
        speed += (out[0] / load - speed) * 0.001 / 0.07
        angle += speed * 0.001
    assert speed == pytest.approx(target, rel=0.02)


def test_no_integration_while_saturated() -> None:
    sc = SpeedControl([CPR], 1.0, 1.0, PERIOD, PWM_MAX, 5.0)
    out = [0]
    sc.reset([0])
    sc.update(PERIOD, [0], [30.0], [250.0], out)
    assert out == [PWM_MAX] and sc._integ == [0.0]
    sc.update(PERIOD, [0], [30.0], [-300.0], out)
    assert out == [-PWM_MAX] and sc._integ == [0.0]


def test_the_band_is_where_the_p_term_gives_5_percent_of_full_power() -> None:
    for robot in ("omni4", "omni3", "mecanum4"):
        cfg = build_config(load_robot(robot))
        assert cfg["speed_kp"] * cfg["speed_band"] == pytest.approx(0.05 * cfg["pwm_max"], rel=1e-5)


def test_the_integral_learns_against_the_target_each_period_was_driven_for() -> None:
    """A wheel that follows a host's ramp reads, each period, the target the period began with, one
    step short of the new one: against the period's own target it integrates nothing (no lag stored
    to carry it past the ramp's end), where the new target's error stored a step a period; the P
    term still answers the new target."""
    cpr, step, periods = 16_000, 2.0, 8  # fine encoders: no rounding in the speeds read
    rad = 2 * math.pi / cpr
    sc = SpeedControl([cpr], 0.5, 1.0, PERIOD, PWM_MAX, 5.0)
    out = [0]
    sc.reset([0])
    counts = 0.0
    for k in range(1, periods + 1):
        counts += step * (k - 1) * 0.01 / rad  # the last period's target, reached
        sc.update(PERIOD, [round(counts)], [step * k], [0.0], out)
    lag = periods * step * 0.01  # what the new targets' errors summed to
    assert abs(sc._integ[0]) < 0.01 * lag
    assert sc.correction[0] == pytest.approx(0.5 * step, abs=0.01)


def test_a_held_target_integrates_at_the_steady_rate() -> None:
    """Once the target has not changed for STEADY_PERIODS periods the integral grows at
    ki_steady / ki of its rate; the correction stays ki times the integral (no jump when the rate
    changes); a target that moves, or is 0, integrates at the plain rate."""
    sc = SpeedControl([CPR], 0.0, 1.0, PERIOD, PWM_MAX, 0.0, ki_steady=2.0)
    out = [0]
    sc.reset([0])
    for _ in range(STEADY_PERIODS):  # the first period is the step from 0 (driven for rest); then it holds
        sc.update(PERIOD, [0], [3.0], [0.0], out)
    assert sc._integ[0] == pytest.approx((STEADY_PERIODS - 1) * 3.0 * 0.01)
    assert sc.correction[0] == pytest.approx((STEADY_PERIODS - 2) * 3.0 * 0.01)  # ki x the integral before
    before = sc._integ[0]
    sc.update(PERIOD, [0], [3.0], [0.0], out)  # held STEADY_PERIODS periods: twice the rate
    assert sc._integ[0] - before == pytest.approx(2 * 3.0 * 0.01)
    assert sc.correction[0] == pytest.approx(before)
    before = sc._integ[0]
    sc.update(PERIOD, [0], [3.1], [0.0], out)  # the target moved: the plain rate again (the period's 3.0)
    assert sc._integ[0] - before == pytest.approx(3.0 * 0.01)
    sc.reset([0])
    for k in range(1, 2 * STEADY_PERIODS + 1):  # a wheel asked to stand still creeps: the plain rate
        sc.update(PERIOD, [k], [0.0], [0.0], out)
    assert sc._integ[0] == pytest.approx(-2 * STEADY_PERIODS * 2 * math.pi / CPR)
    band = 5.0
    sc = SpeedControl([CPR], 0.0, 1.0, PERIOD, PWM_MAX, band, ki_steady=2.0)
    sc.reset([0])
    for _ in range(2 * STEADY_PERIODS):  # a step held, the wheel still far below: the rise's rate
        sc.update(PERIOD, [0], [4 * band], [0.0], out)
    assert sc._integ[0] == pytest.approx((2 * STEADY_PERIODS - 1) * 4 * band * 0.01 / 17)
    plain = SpeedControl([CPR], 0.0, 1.0, PERIOD, PWM_MAX)  # no ki_steady: the plain rate throughout
    plain.reset([0])
    for _ in range(2 * STEADY_PERIODS):
        plain.update(PERIOD, [0], [3.0], [0.0], out)
    assert plain._integ[0] == pytest.approx((2 * STEADY_PERIODS - 1) * 3.0 * 0.01)


def test_the_steady_integral_is_twice_the_loop_s() -> None:
    for robot in ("omni4", "omni3", "mecanum4"):
        cfg = build_config(load_robot(robot))
        assert cfg["speed_ki_steady"] == pytest.approx(2.0 * cfg["speed_ki"], rel=1e-5)
