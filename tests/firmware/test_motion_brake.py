"""The executor's slew of a VEL without a planned acceleration and its brake to rest (closed loop)."""

from __future__ import annotations

import math

import pytest

from omnibot.sim import SimDevice
from tests.firmware.conftest import make_rig


def test_a_vel_that_runs_out_on_the_closed_loop_is_slewed_to_rest() -> None:
    rig = make_rig()  # omni4: 2 m/s^2, 20 rad/s^2
    ex = rig.ctrl.executor
    assert rig.cmd("MODE,2") == ["OK"]
    assert rig.cmd("VEL,60,0,90,100") == ["OK"]
    assert ex._twist == pytest.approx([0.6, 0.0, math.radians(90)])  # a VEL is driven as asked
    rig.run(100)  # the watchdog runs out: braking from the twist driven, 0.02 m/s a 10 ms period
    assert ex._braking and ex.moving
    assert ex._ref[0] == pytest.approx(0.58, abs=0.011)
    assert ex._acc_on and ex._acc[0] == pytest.approx(-2.0, abs=0.35)  # the slew's torque fed forward
    rig.run(300)
    assert ex._ref == [0.0, 0.0, 0.0] and not ex._slewing
    lines = rig.run(100)  # the fake wheels never turned: at rest at the first window after the slew
    assert lines == ["IDLE"] and not ex.moving


def test_a_vel_that_runs_out_in_open_loop_stops_the_motors_at_once() -> None:
    rig = make_rig()
    assert rig.cmd("VEL,60,0,0,100") == ["OK"]
    assert rig.run(101) == ["IDLE"]
    assert rig.hal.powers == [0, 0, 0, 0]


def _let_go(robot: str, speed: float) -> tuple[float, float, float]:
    """Drive ``robot`` at ``speed`` m/s on the closed loop as a person's 20 Hz VELs would, then fall
    silent (the watchdog runs out): the distance the truth travelled after the last VEL, the time to
    the IDLE event and the body's largest deceleration (m/s^2, over 50 ms) on the way."""
    dev = SimDevice(robot, surface="wood", seed=1)
    dev.command("MODE,2", 0.05)
    for _ in range(round(speed / 1.0 / 0.05) + 20):  # up to speed at 1 m/s^2, then held
        dev.command(f"VEL,{round(speed * 100)},0,0,250", 0.05)
    x0, t0 = dev.sim.pose.x, dev.sim.time
    idle, v, decel = None, dev.sim.twist.vx, 0.0
    while idle is None and dev.sim.time - t0 < 6.0:
        if b"IDLE" in dev.run(0.05):
            idle = dev.sim.time - t0
        decel, v = max(decel, (v - dev.sim.twist.vx) / 0.05), dev.sim.twist.vx
    assert idle is not None and abs(dev.sim.twist.vx) < 0.01
    return dev.sim.pose.x - x0, idle, decel


@pytest.mark.parametrize(
    ("robot", "speed", "accel"), [("omni3", 2.5, 2.5), ("omni4", 0.6, 2.0), ("mecanum4", 0.6, 2.0)]
)
def test_a_robot_let_go_brakes_to_rest_at_its_acceleration_limit(
    robot: str, speed: float, accel: float
) -> None:
    """The watchdog's 0.25 s at speed, then v^2 / 2a slewed down (omni3, 30 kg at 2.5 m/s: 1.9 m;
    it coasted 10 m and more when the motors went off at once); the wheels never lock (the body
    never stops harder than the limit)."""
    travelled, took, decel = _let_go(robot, speed)
    assert travelled == pytest.approx(speed * 0.25 + speed**2 / (2 * accel), rel=0.15)
    assert took < 0.25 + speed / accel + 0.25  # the watchdog, the slew, the wheels' lag and rest windows
    assert decel < 1.3 * accel
