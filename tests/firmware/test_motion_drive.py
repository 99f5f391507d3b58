"""The executor's drive (motion_drive.py): what a twist and a VEL's planned acceleration feed each wheel."""

from __future__ import annotations

import math

import pytest

from omnibot.robot import kinematics, load_robot
from omnibot.sim import SimDevice
from tests.firmware.conftest import Rig, make_rig


def test_a_wheel_that_mostly_turns_the_body_is_fed_what_turns_it_on_the_closed_loop() -> None:
    """omni4's arc (0.3 m/s turning at 0.5 rad/s): its two wheels that only turn the body (rim 0.049
    m/s) are fed at least ROTATE's K K_r at their own speed (the turning part's flat K_t gave them
    8-14 counts where 33-37 turn them); the driving pair keeps the power model's feedforward."""
    dev = SimDevice("omni4", surface="wood", seed=1)
    ex = dev.controller.executor
    cal = ex.model.cal
    dev.command("MODE,2", 0.02)
    dev.command("VEL,30,0,29,200", 0.02)
    turning = [i for i, row in enumerate(ex.model.rim) if abs(row[0] * 0.3) < 1e-9]
    assert len(turning) == 2
    for i in range(ex.n):
        u = abs(ex._target[i] * ex._radius[i])
        if i in turning:
            assert abs(ex._ff[i]) == pytest.approx(cal.k * cal.k_r(cal.k * u) * u)
            assert abs(ex._ff[i]) > 2.5 * abs(ex.model.raw[i])  # K_t's was under 0.4 of it
        else:
            assert ex._ff[i] == pytest.approx(ex.model.raw[i])


def test_vel_feeds_its_planned_acceleration_forward_in_the_closed_loop() -> None:
    """VEL's fifth field, A cm/s^2 along (VX, VY), adds to each wheel's feedforward its share of the
    body's acceleration (body_ff) and its own inertia's (wheel_ff times its angular acceleration),
    for as long as that VEL holds."""
    rig = make_rig()
    ex = rig.ctrl.executor
    assert rig.cmd("MODE,2") == ["OK"]
    assert rig.cmd("VEL,30,40,0,200") == ["OK"]
    plain = list(ex._ff)
    assert rig.cmd("VEL,30,40,0,200,150") == ["OK"]  # 1.5 m/s^2 along (0.6, 0.8)
    body, own, J = rig.config["body_ff"], rig.config["wheel_ff"], rig.config["J"]
    rows = [[b[k] + f * j[k] for k in (0, 1)] for b, f, j in zip(body, own, J, strict=True)]
    for i in range(4):
        assert ex._ff[i] - plain[i] == pytest.approx(1.5 * (0.6 * rows[i][0] + 0.8 * rows[i][1]))
    assert rig.cmd("VEL,30,40,0,200,-150") == ["OK"]  # braking: the other way
    for i in range(4):
        assert ex._ff[i] - plain[i] == pytest.approx(-1.5 * (0.6 * rows[i][0] + 0.8 * rows[i][1]))
    assert rig.cmd("VEL,30,40,0,200") == ["OK"]  # the next VEL without A: none
    assert ex._ff == pytest.approx(plain)
    assert rig.cmd("VEL,0,0,90,200,150") == ["OK"]  # turning in place: no translation to speed up
    turning = list(ex._ff)
    assert rig.cmd("VEL,0,0,90,200") == ["OK"]
    assert ex._ff == turning


def _added_ff(rig: Rig, vel: str, accel: str) -> list[float]:
    """Each wheel's feedforward with ``VEL,<vel>,<accel>`` less that of ``VEL,<vel>`` (closed loop)."""
    assert rig.cmd("MODE,2") == ["OK"]
    assert rig.cmd(f"VEL,{vel}") == ["OK"]
    plain = list(rig.ctrl.executor._ff)
    assert rig.cmd(f"VEL,{vel},{accel}") == ["OK"]
    return [a - b for a, b in zip(rig.ctrl.executor._ff, plain, strict=True)]


def _newtons_per_count(robot: str) -> list[float]:
    """The traction force (N, along each wheel's drive direction) of one PWM count of current-making
    voltage: the motor's torque constant, gear, efficiency and winding, the wheel's radius."""
    description = load_robot(robot)
    out = []
    for w in description.wheels:
        m = w.motor
        amps = (description.battery.voltage - m.driver_drop) / m.pwm_max / m.resistance
        out.append(
            amps * m.torque_constant * m.gear_ratio * m.gear_efficiency / (w.radius * math.cos(w.gamma))
        )
    return out


@pytest.mark.parametrize("robot", ["omni4", "omni3", "mecanum4"])
@pytest.mark.parametrize(
    ("vel", "accel"),
    [
        ("30,40,0,200", "100,-50,0"),  # speeding up along x, braking sideways, no turn
        ("30,0,60,200", "0,31,0"),  # a steady circle to the left: the centripetal 0.3 x 1.047 m/s^2
        ("-20,25,-45,200", "-80,35,-120"),  # everything at once
        ("0,0,90,200", "0,0,300"),  # spinning up in place
    ],
)
def test_vel_body_acceleration_gives_the_body_its_force_and_torque(robot: str, vel: str, accel: str) -> None:
    """Version 4's VEL,VX,VY,W,T,AX,AY,AW: the traction forces the wheels' added feedforward makes
    (without the wheels' own inertia) sum to the body's mass times (AX, AY) and its yaw inertia times
    AW: each wheel gets its share with the right sign (a wrong sign or wheel breaks the sums)."""
    description = load_robot(robot)
    rig = make_rig(robot, wheel_ff=[0.0] * description.n_wheels)
    added = _added_ff(rig, vel, accel)
    forces = [c * n for c, n in zip(added, _newtons_per_count(robot), strict=True)]
    traction, _ = kinematics.robot_contact_rows(description)
    ax, ay, aw = (int(v) for v in accel.split(","))
    want = [
        description.mass * ax * 0.01,
        description.mass * ay * 0.01,
        description.yaw_inertia * math.radians(aw),
    ]
    assert list(traction.T @ forces) == pytest.approx(want, abs=1e-3 * max(1.0, *map(abs, want)))


def test_vel_body_acceleration_turns_each_wheel_at_the_rate_of_its_target() -> None:
    """The wheels' own inertia needs their angular acceleration, the rate at which each wheel's
    target changes: the body's acceleration less the turn's w x v (the body's axes turn with it).
    Driving straight in the world at a steady speed while spinning (no acceleration of the centre),
    the body-frame velocity turns the other way: the added power follows the targets' change."""
    rig = make_rig("omni4", body_ff=[[0.0, 0.0, 0.0]] * 4)
    ex = rig.ctrl.executor
    own = rig.config["wheel_ff"]
    added = _added_ff(rig, "90,0,90,200", "0,0,0")
    before = list(ex._target)
    dt = 0.05  # the body turned by 4.5 degrees: the world velocity (0.9, 0) is now at -4.5 in the body
    turned = math.radians(90) * dt
    assert rig.cmd(f"VEL,{90 * math.cos(turned):.0f},{-90 * math.sin(turned):.0f},90,200") == ["OK"]
    rates = [(a - b) / dt for a, b in zip(ex._target, before, strict=True)]  # rad/s^2
    assert [a / f for a, f in zip(added, own, strict=True)] == pytest.approx(rates, rel=0.05, abs=3.0)
    assert rates[0] < -50 and rates[2] > 50  # wheels 0 and 2 (driving y) take the turn of the velocity


def test_vel_acceleration_leaves_the_open_loop_powers_alone() -> None:
    rig = make_rig()
    assert rig.cmd("VEL,30,40,0,200") == ["OK"]
    plain = rig.status()
    assert rig.cmd("VEL,30,40,0,200,150") == ["OK"]
    assert rig.status() == plain
