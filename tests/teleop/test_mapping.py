"""The pure mapping: deadzone, enable and turbo buttons, limits that keep the direction."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from omnibot.client import Limits
from omnibot.motion import Twist
from omnibot.robot import load_robot
from omnibot.teleop.config import TeleopConfig
from omnibot.teleop.mapping import (
    JoyState,
    TwistLimits,
    TwistRamp,
    deadzone,
    fractions_to_twist,
    joy_to_command,
    limit_twist,
)

SEED = TeleopConfig()


def pad(axes: dict[int, float], *pressed: int) -> JoyState:
    return JoyState(
        tuple(axes.get(i, 0.0) for i in range(8)), tuple(int(b in pressed) for b in range(12)), time=0.0
    )


def test_deadzone_is_joy_nodes() -> None:
    assert deadzone(0.05, 0.05) == 0.0
    assert deadzone(-0.04, 0.05) == 0.0
    assert deadzone(1.0, 0.05) == 1.0
    assert deadzone(-1.0, 0.05) == -1.0
    assert deadzone(0.525, 0.05) == pytest.approx(0.5)
    assert deadzone(2.0, 0.05) == 1.0
    assert deadzone(math.nan, 0.05) == 0.0


def test_enable_button_is_required() -> None:
    cmd = joy_to_command(SEED, pad({3: 1.0, 1: 1.0, 0: 1.0}))
    assert not cmd.enabled
    assert cmd.twist.is_zero
    free = SEED.model_copy(update={"require_enable_button": False})
    assert joy_to_command(free, pad({3: 0.5})).enabled


def test_seed_axes_and_scales() -> None:
    cmd = joy_to_command(SEED, pad({3: 0.5, 1: -0.25, 0: 0.1}, 7))
    assert cmd.enabled and not cmd.turbo
    dz = SEED.deadzone
    assert cmd.twist.vx == pytest.approx(-3.5 * (0.5 - dz) / (1 - dz))
    assert cmd.twist.vy == pytest.approx(3.5 * -(0.25 - dz) / (1 - dz))
    assert cmd.twist.w == pytest.approx(3.5 * (0.1 - dz) / (1 - dz))


def test_turbo_button_drives_on_its_own_with_turbo_scales() -> None:
    cmd = joy_to_command(SEED, pad({3: 1.0}, 6))
    assert cmd.enabled and cmd.turbo
    assert cmd.twist == Twist(-50.0, 0.0, 0.0)


def test_missing_axes_and_buttons_read_zero() -> None:
    small = JoyState(axes=(0.5,), buttons=(1,), time=0.0)  # a pad with 1 axis and 1 button
    assert not joy_to_command(SEED, small).enabled
    cfg = SEED.model_copy(update={"enable_button": 0})
    cmd = joy_to_command(cfg, small)
    assert cmd.enabled
    assert cmd.twist.vx == 0.0 and cmd.twist.vy == 0.0 and cmd.twist.w > 0


def test_limits_from_the_controller_bounds() -> None:
    limits = Limits.from_robot("omni4")
    lim = TwistLimits.from_limits(limits)
    assert lim.speed == pytest.approx(0.99)  # 1 cm/s and 1 degree/s inside: rounding never crosses them
    assert lim.rate == pytest.approx(math.radians(limits.rate_max_dps - 1))
    assert round(math.degrees(lim.rate)) < limits.rate_max_dps
    capped = TwistLimits.from_limits(Limits.from_robot("omni4"), SEED.model_copy(update={"speed_max": 0.3}))
    assert capped.speed == 0.3


@given(
    st.floats(-100, 100, allow_nan=False),
    st.floats(-100, 100, allow_nan=False),
    st.floats(-100, 100, allow_nan=False),
)
def test_limit_keeps_direction_and_ratio(vx: float, vy: float, w: float) -> None:
    lim = TwistLimits(speed=1.0, rate=2.0)
    out = limit_twist(Twist(vx, vy, w), lim)
    assert math.hypot(out.vx, out.vy) <= lim.speed + 1e-9
    assert abs(out.w) <= lim.rate + 1e-9
    # the common factor, read off the largest component (a subnormal one underflows when scaled)
    given, got = max((vx, out.vx), (vy, out.vy), (w, out.w), key=lambda pair: abs(pair[0]))
    k = got / given if given else 1.0
    assert 0 < k <= 1.0
    assert (
        out.vx == pytest.approx(vx * k) and out.vy == pytest.approx(vy * k) and out.w == pytest.approx(w * k)
    )


def test_fractions_are_of_the_limits() -> None:
    lim = TwistLimits(speed=0.5, rate=2.0)
    assert fractions_to_twist(1.0, 0.0, 0.0, lim) == Twist(0.5, 0.0, 0.0)
    diag = fractions_to_twist(1.0, 1.0, 0.0, lim)
    assert math.hypot(diag.vx, diag.vy) == pytest.approx(0.5) and diag.vx == pytest.approx(diag.vy)


def test_twist_limits_take_the_robots_accelerations() -> None:
    robot = load_robot("omni3")
    limits = TwistLimits.from_limits(Limits.from_robot(robot), SEED, robot)
    assert (limits.accel, limits.angular_accel) == (2.5, 10.0)
    assert math.isinf(TwistLimits.from_limits(Limits.from_robot(robot), SEED).accel)  # no robot: at once


def test_a_floor_with_less_grip_shares_the_accelerations_out() -> None:
    robot = load_robot("omni3")  # 30 kg: its grip holds 0.72 of its accelerations on wood, 0.68 on carpet
    bounds = Limits.from_robot(robot)
    unknown = TwistLimits.from_limits(bounds, SEED, robot)
    wood = TwistLimits.from_limits(bounds, SEED, robot, "wood")
    carpet = TwistLimits.from_limits(bounds, SEED, robot, "carpet")
    assert unknown.grip is None and unknown.grip_at(0.3) == 1.0  # a floor not known: today's limits
    assert (wood.accel, wood.angular_accel, wood.speed) == (
        unknown.accel,
        unknown.angular_accel,
        unknown.speed,
    )
    assert wood.grip is not None and wood.grip[0][-1] == pytest.approx(wood.speed)  # up to the top speed
    for v in (0.0, 0.3, 1.0):
        assert 0.0 < carpet.grip_at(v) < wood.grip_at(v) < 1.0
    ramp = TwistRamp(carpet)
    ramp.step(Twist(1.0, 0.0, 5.0), 0.05)
    assert ramp.body_accel[0] == pytest.approx(2.5 * carpet.grip_at(0.0))
    assert ramp.body_accel[2] == pytest.approx(10.0 * carpet.grip_at(0.0))


def test_a_ramp_takes_the_grips_share_at_the_speed_it_ramps_from() -> None:
    ramp = TwistRamp(TwistLimits(2.0, 5.0, accel=2.0, angular_accel=10.0, grip=((0.0, 1.0), (1.0, 0.5))))
    assert ramp.step(Twist(2.0, 0.0, 5.0), 0.05) == pytest.approx(Twist(0.1, 0.0, 0.5))  # at rest: all
    ramp.reset(Twist(0.5, 0.0, 0.0))
    assert ramp.step(Twist(2.0, 0.0, 5.0), 0.05) == pytest.approx(Twist(0.575, 0.0, 0.375))  # 0.75 at 0.5
    ramp.reset(Twist(2.0, 0.0, 0.0))  # past the table: its last share
    assert ramp.step(Twist(0.0, 0.0, 0.0), 0.05) == pytest.approx(Twist(1.95, 0.0, 0.0))


def test_a_ramp_changes_the_twist_by_at_most_the_accelerations() -> None:
    ramp = TwistRamp(TwistLimits(1.0, 5.0, accel=2.0, angular_accel=10.0))
    step = ramp.step(Twist(0.3, 0.4, 1.0), 0.05)  # 0.1 m/s along (0.6, 0.8), 0.5 rad/s
    assert step == pytest.approx(Twist(0.06, 0.08, 0.5))
    assert ramp.body_accel == pytest.approx((1.2 - 0.5 * 0.08, 1.6 + 0.5 * 0.06, 10.0))
    for _ in range(4):
        ramp.step(Twist(0.3, 0.4, 1.0), 0.05)
    assert ramp.twist == pytest.approx(Twist(0.3, 0.4, 1.0))
    assert ramp.step(Twist(0.3, 0.4, 1.0), 0.05) == pytest.approx(Twist(0.3, 0.4, 1.0))
    assert ramp.body_accel == pytest.approx((-0.4, 0.3, 0.0))  # arrived: only the turning axes' part
    assert ramp.step(Twist(0.0, 0.0, 0.0), 0.0) == ramp.twist  # no time: no change
    assert not TwistRamp(TwistLimits(1.0, 5.0)).limited
