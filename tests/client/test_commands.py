"""SI -> protocol commands: conversion, rounding to the protocol's resolution, checks before sending."""

from __future__ import annotations

import math

import pytest

from omnibot.client import Limits
from omnibot.client import commands as c
from omnibot.protocol import codes
from omnibot.protocol.messages import Cal, Delta, Mode, Move, Power, Rotate, Sonar, Telem, Vel
from omnibot.robot import (
    CalibrationSpec,
    CourseTable,
    MotorMapSpec,
    PiecewiseLinear,
    ReachSpec,
    RollerDragSpec,
)

OMNI4 = Limits.from_robot("omni4")
ANY = Limits()


def test_limits_from_robot_match_the_firmware_config() -> None:
    assert OMNI4.robot == "omni4"
    assert (OMNI4.distance_max_cm, OMNI4.speed_min_cms, OMNI4.speed_max_cms) == (500.0, 30.0, 100.0)
    assert (OMNI4.curvature_max, OMNI4.motors, OMNI4.pwm_max) == (100.0, 4, 255)
    assert OMNI4.sonar_period_min_ms == (60,) and OMNI4.has_encoders
    assert math.isclose(OMNI4.rate_max_dps, math.degrees(15.7))
    assert ANY.robot is None and ANY.motors is None


def test_move_converts_and_rounds() -> None:
    assert c.move(OMNI4, 0.5, 0.4) == Move(50, 40, 0, 0)
    assert c.move(OMNI4, 0.123, 0.456, math.radians(10.4), 2.04) == Move(12, 46, 10, 20)
    assert c.move(OMNI4, -0.2, 0.3, -math.pi / 2) == Move(-20, 30, -90, 0)
    assert c.move(OMNI4, math.inf, 0.4) == Move(codes.INF, 40, 0, 0)
    assert c.move(OMNI4, -math.inf, 0.4) == Move(-codes.INF, 40, 0, 0)


@pytest.mark.parametrize(
    ("args", "words"),
    [
        ((5.0, 0.4), "distance 5 is 500 cm, outside abs(L) < 500 cm"),
        ((0.5, 0.2), "speed 0.2 is 20 cm/s, outside 30 <= abs(V) <= 100 cm/s"),
        ((0.5, 1.2), "speed"),
        ((0.5, 0.0), "speed"),
        ((0.5, 0.4, 2 * math.pi), "course"),
        ((0.5, 0.4, 0.0, 10.0), "curvature 10 is 100 1/(1000 cm)"),
        ((math.nan, 0.4), "finite"),
        ((0.5, math.inf), "finite"),
        ((400.0, 0.4), "16-bit"),
    ],
)
def test_move_rejects_out_of_range(args: tuple[float, ...], words: str) -> None:
    with pytest.raises(ValueError, match="MOVE") as info:
        c.move(OMNI4, *args)
    assert words in str(info.value)


def test_protocol_only_limits_allow_what_the_protocol_allows() -> None:
    assert c.move(ANY, 20.0, 2.0) == Move(2000, 200, 0, 0)
    with pytest.raises(ValueError, match=r"use math\.inf"):
        c.move(ANY, 300.0, 1.0)  # 30000 cm would mean INF
    with pytest.raises(ValueError, match="speed"):
        c.move(ANY, 1.0, 0.001)  # rounds to 0 cm/s


def test_move_type_errors() -> None:
    with pytest.raises(TypeError):
        c.move(OMNI4, "1", 0.4)  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        c.move(OMNI4, True, 0.4)


def test_delta() -> None:
    assert c.delta(OMNI4, course=math.radians(10), repeat=36) == Delta(0, 0, 10, 0, 36)
    assert c.delta(OMNI4, 0.01, -0.05, repeat=math.inf) == Delta(1, -5, 0, 0, codes.INF)
    assert c.delta(OMNI4, 9.99, 2.0, math.radians(719), 19.9) == Delta(999, 200, 719, 199, 0)
    for kwargs in ({"distance": 10.0}, {"speed": 2.01}, {"course": math.radians(720)}, {"curvature": 20.0}):
        with pytest.raises(ValueError, match="DELTA"):
            c.delta(OMNI4, **kwargs)
    for repeat in (-1, 30001, 1.5, -math.inf, True):
        with pytest.raises(ValueError, match="repeat"):
            c.delta(OMNI4, repeat=repeat)


def test_rotate() -> None:
    assert c.rotate(OMNI4, math.pi, math.pi / 2) == Rotate(180, 90)
    assert c.rotate(OMNI4, -math.inf, 1.0) == Rotate(-codes.INF, 57)
    assert c.rotate(OMNI4, 10 * math.pi, -2.0) == Rotate(1800, -115)
    with pytest.raises(ValueError, match="rate"):
        c.rotate(OMNI4, 1.0, 0.001)
    with pytest.raises(ValueError, match="rate"):
        c.rotate(OMNI4, 1.0, 15.7)  # 900 deg/s, not below the limit
    with pytest.raises(ValueError, match="angle"):
        c.rotate(OMNI4, math.radians(30000), 1.0)


def test_power() -> None:
    assert c.power(OMNI4, 0.25, [10, -20, 255, -255]) == Power(250, (10, -20, 255, -255))
    with pytest.raises(ValueError, match="4 powers"):
        c.power(OMNI4, 0.25, [10, 20])
    with pytest.raises(ValueError, match=r"1\.\.4"):
        c.power(ANY, 0.25, [1, 2, 3, 4, 5])
    with pytest.raises(ValueError, match="power 3 = 256"):
        c.power(OMNI4, 0.25, [0, 0, 256, 0])
    with pytest.raises(TypeError, match="integer"):
        c.power(OMNI4, 0.25, [0, 0, 1.5, 0])  # type: ignore[list-item]
    for t in (0.0, 0.0004, 30.001):
        with pytest.raises(ValueError, match="time"):
            c.power(OMNI4, t, [0, 0, 0, 0])


def test_vel() -> None:
    assert c.vel(OMNI4, 0.35, -0.2, math.radians(45), 0.1) == Vel(35, -20, 45, 100)
    with pytest.raises(ValueError, match="exceeds"):
        c.vel(OMNI4, 0.8, 0.8, 0.0, 0.1)
    # within omni4's 1 m/s as asked, past it only as rounded to whole cm/s (71, 71: 100.4 cm/s)
    assert c.vel(OMNI4, 0.707, 0.707, 0.0, 0.1) == Vel(70, 70, 0, 100)
    assert c.vel(OMNI4, -0.707, 0.707, 0.0, 0.1) == Vel(-70, 70, 0, 100)
    with pytest.raises(ValueError, match="exceeds"):
        c.vel(OMNI4, 0.7072, 0.7072, 0.0, 0.1)  # 1.00015 m/s: over it as asked
    with pytest.raises(ValueError, match="w"):
        c.vel(OMNI4, 0.0, 0.0, 16.0, 0.1)
    for t in (0.0, 1.001, 2.0):
        with pytest.raises(ValueError, match="timeout"):
            c.vel(OMNI4, 0.1, 0.0, 0.0, t)
    assert c.vel(OMNI4, 0.35, -0.2, 0.0, 0.1, accel=1.4) == Vel(35, -20, 0, 100, 140)
    assert c.vel(OMNI4, 0.35, -0.2, 0.0, 0.1, accel=-0.014).params() == (35, -20, 0, 100, -1)
    assert c.vel(OMNI4, 0.35, -0.2, 0.0, 0.1, accel=0.0).params() == (35, -20, 0, 100)
    with pytest.raises(ValueError, match="VEL accel 400 is 40000 cm/s\\^2, outside the protocol's 16-bit"):
        c.vel(OMNI4, 0.1, 0.0, 0.0, 0.1, accel=400.0)
    with pytest.raises(ValueError, match="VEL accel: expected a finite number"):
        c.vel(OMNI4, 0.1, 0.0, 0.0, 0.1, accel=math.nan)


def test_mode() -> None:
    assert c.mode(OMNI4, 3) == Mode(3)
    with pytest.raises(ValueError, match="use_binary"):
        c.mode(OMNI4, codes.MODE_BINARY)
    assert c.mode(OMNI4, codes.MODE_REFUSE_UNCOVERED) == Mode(8)
    with pytest.raises(ValueError, match="bits"):
        c.mode(OMNI4, 64)
    assert c.mode(OMNI4, codes.MODE_CHECKED_TEXT) == Mode(16)
    assert c.mode(OMNI4, codes.MODE_SEQUENCED_TEXT) == Mode(32)
    with pytest.raises(ValueError, match="encoders"):
        c.mode(Limits(has_encoders=False, robot="bare"), codes.MODE_CLOSED_LOOP)


def test_sonar_and_telem() -> None:
    assert c.sonar(OMNI4, 1, 0.1, 0.2, 3.0, 0.25) == Sonar(1, 100, 20, 300, 25)
    assert c.sonar(OMNI4, 1, 0) == Sonar(1, 0, 0, 0, 0)
    with pytest.raises(ValueError, match=r"numbered 1\.\.1"):
        c.sonar(OMNI4, 2, 0.1)
    with pytest.raises(ValueError, match="period"):
        c.sonar(OMNI4, 1, 0.05)
    with pytest.raises(ValueError, match="high"):
        c.sonar(OMNI4, 1, 0.1, 0.0, 5.01)
    assert c.sonar(ANY, 3, 0.06) == Sonar(3, 60, 0, 0, 0)
    assert c.telem(OMNI4, 0.05) == Telem(50, 255)
    assert c.telem(OMNI4, 0, 0) == Telem(0, 0)
    with pytest.raises(ValueError, match="period"):
        c.telem(OMNI4, 0.005)
    with pytest.raises(ValueError, match="mask"):
        c.telem(OMNI4, 0.1, 256)


def test_cal_and_calibration_upload() -> None:
    assert c.cal(OMNI4, 1, 0, 40, 1300) == Cal(1, 0, 40, 1300)
    with pytest.raises(ValueError, match="16-bit"):
        c.cal(OMNI4, 1, 0, 40, 70000)
    full = CalibrationSpec(
        k=220.0,
        k_t=PiecewiseLinear(x=(40.0, 255.0), y=(1.3, 0.95)),
        k_l=CourseTable(
            courses_deg=(0.0, 45.0),
            curves=(PiecewiseLinear(x=(40.0,), y=(1.4,)), PiecewiseLinear(x=(40.0,), y=(1.1,))),
        ),
    )
    assert c.calibration(full) == [
        Cal(0, 0, 0, 2200),
        Cal(1, 0, 40, 1300),
        Cal(1, 1, 255, 950),
        Cal(10, -1, 0, 0),
        Cal(10, 0, 40, 1400),
        Cal(11, -1, 45, 0),
        Cal(11, 0, 40, 1100),
        Cal(12, codes.CAL_KL_DROP, 0, 0),  # curves the controller held beyond these are dropped
    ]
    motors = MotorMapSpec(
        offset=(0.0, 38.25),
        gain=(PiecewiseLinear(x=(0.0,), y=(1.0,)), PiecewiseLinear(x=(50.0, 200.0), y=(1.1, 0.9))),
    )
    # without a motor map, the identity when the robot's motors are known
    assert c.calibration(CalibrationSpec(k=220.0)) == [Cal(0, 0, 0, 2200)]
    no_drag = [
        Cal(codes.CAL_ROLLER_COS, 0, 0, 0),
        Cal(codes.CAL_ROLLER_SIN, 0, 0, 0),
        Cal(codes.CAL_ROLLER_COS, 1, 0, 0),
        Cal(codes.CAL_ROLLER_SIN, 1, 0, 0),
        Cal(codes.CAL_ROLLER_COAST, 0, 0, 0),
    ]
    assert c.calibration(CalibrationSpec(k=220.0), motors=2)[1:] == [
        Cal(codes.CAL_OFFSET, 0, 0, 0),
        Cal(codes.CAL_GAIN, 0, 0, 1000),
        Cal(codes.CAL_SPEED, 0, 0, 0),
        Cal(codes.CAL_OFFSET, 1, 0, 0),
        Cal(codes.CAL_GAIN + 1, 0, 0, 1000),
        Cal(codes.CAL_SPEED, 1, 0, 0),
        *no_drag,
        Cal(codes.CAL_REACH, 0, 0, 0),  # no reach: the controller runs every MOVE as asked
    ]
    # the motor model's speed terms, 0.1 counts per m/s (a map without them sends 0: no speed term)
    speedy = motors.model_copy(update={"speed": (21.64, -23.9)})
    sent = c.calibration(CalibrationSpec(k=220.0, motors=speedy), motors=2)
    assert [m for m in sent if m.table == codes.CAL_SPEED] == [
        Cal(codes.CAL_SPEED, 0, 0, 216),
        Cal(codes.CAL_SPEED, 1, 0, -239),
    ]
    drag = RollerDragSpec(
        cos=(-4.96, 0.0), sin=(0.35, 0.0), coast=PiecewiseLinear(x=(0.0, 0.64), y=(0.0, 0.34))
    )
    assert c.calibration(CalibrationSpec(k=220.0, rollers=drag))[1:] == [
        Cal(codes.CAL_ROLLER_COS, 0, 0, -50),
        Cal(codes.CAL_ROLLER_SIN, 0, 0, 4),
        Cal(codes.CAL_ROLLER_COS, 1, 0, 0),
        Cal(codes.CAL_ROLLER_SIN, 1, 0, 0),
        Cal(codes.CAL_ROLLER_COAST, 0, 0, 0),
        Cal(codes.CAL_ROLLER_COAST, 1, 64, 340),
    ]
    with pytest.raises(ValueError, match="roller drag: 2 wheels for a robot with 4"):
        c.calibration(CalibrationSpec(k=220.0, rollers=drag), motors=4)
    close = drag.model_copy(update={"coast": PiecewiseLinear(x=(0.5, 0.503), y=(0.1, 0.2))})
    with pytest.raises(ValueError, match="1 cm/s apart"):
        c.calibration(CalibrationSpec(k=220.0, rollers=close))
    # the reach: folded courses in degrees, speeds in cm/s (rounded down: never faster than measured)
    reach = ReachSpec(courses_deg=(0.0, 15.0, 30.0, 45.0), speed=(0.9, 0.815, 0.68, 0.775))
    assert c.calibration(CalibrationSpec(k=220.0, reach=reach))[1:] == [
        Cal(codes.CAL_REACH, 0, 0, 90),
        Cal(codes.CAL_REACH, 1, 15, 81),
        Cal(codes.CAL_REACH, 2, 30, 68),
        Cal(codes.CAL_REACH, 3, 45, 77),
    ]
    with pytest.raises(ValueError, match="1 degree apart"):
        c.calibration(CalibrationSpec(k=220.0, reach=ReachSpec(courses_deg=(30.0, 30.2), speed=(0.5, 0.6))))
    with pytest.raises(ValueError, match="2 motors for a robot with 4"):
        c.calibration(CalibrationSpec(k=220.0, motors=motors), motors=4)
    assert c.calibration(CalibrationSpec(k=220.0, motors=motors))[1:] == [
        Cal(codes.CAL_OFFSET, 0, 0, 0),
        Cal(codes.CAL_GAIN, 0, 0, 1000),
        Cal(codes.CAL_SPEED, 0, 0, 0),
        Cal(codes.CAL_OFFSET, 1, 0, 382),
        Cal(codes.CAL_GAIN + 1, 0, 50, 1100),
        Cal(codes.CAL_GAIN + 1, 1, 200, 900),
        Cal(codes.CAL_SPEED, 1, 0, 0),
    ]
