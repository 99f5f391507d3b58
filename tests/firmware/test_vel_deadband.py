"""An open-loop VEL whose slower wheels get less power than turns them: those wheels are set to 0
and WARN 12 says so, once per VEL stream; the closed loop and the other commands are left alone.

omni4 with its preset calibration: the K_l tables' intercept (the dead band they were fitted from)
is about 44 PWM counts; 0.2 m/s forward + 0.1 m/s sideways gives the sideways pair 41.
"""

from __future__ import annotations

import pytest

from omnibot.firmware.calibration import Calibration
from omnibot.firmware.config import build_config
from omnibot.firmware.power import WEAK, PowerModel
from omnibot.protocol import codes
from omnibot.robot import load_robot
from tests.firmware.conftest import Rig

WARN_12 = f"WARN,12,{codes.TEXTS[codes.W_POWER_TOO_LOW]}"


@pytest.fixture
def omni4() -> Rig:
    return Rig(build_config(load_robot("omni4")))


def test_the_calibrations_dead_band_is_the_intercept_of_its_lowest_knots() -> None:
    cal = Calibration(build_config(load_robot("omni4")))
    assert cal.start_power() == pytest.approx(43.58, abs=0.01)  # 2 x 10 x 5.316 - 20 x 3.137
    flat = Calibration(
        build_config(load_robot("omni4")) | {"kl_tables": [[[0.0], [1.0]]], "kl_courses": [0.0]}
    )
    assert flat.start_power() == 0.0  # seed 000's flat factors say nothing about the dead band


def test_a_weak_wheel_of_an_open_loop_vel_is_set_to_0_with_warn_12(omni4: Rig) -> None:
    assert omni4.cmd("VEL,20,10,0,500") == ["OK", WARN_12]
    assert omni4.hal.powers == [0, 82, 0, -82]  # the sideways pair (41) would not turn
    assert omni4.cmd("VEL,20,10,0,500") == ["OK"]  # once per VEL stream
    assert omni4.run(100) == []
    assert omni4.hal.powers == [0, 82, 0, -82]  # every control period (the roller drag's too)
    assert omni4.cmd("VEL,0,10,0,500") == ["OK"]  # 63 on its own: turns
    assert omni4.hal.powers == [63, 0, -63, 0]


def test_a_vel_below_every_wheels_dead_band_stops_them_all(omni4: Rig) -> None:
    assert omni4.cmd("VEL,5,0,0,500") == ["OK", WARN_12]
    assert omni4.hal.powers == [0, 0, 0, 0]


def test_the_closed_loop_and_move_are_left_alone(omni4: Rig) -> None:
    assert omni4.cmd("MODE,2") == ["OK"]
    assert omni4.cmd("VEL,20,10,0,500") == ["OK"]
    assert 0 < omni4.hal.powers[0] < 44  # the speed loop raises it as the wheel lags
    assert omni4.cmd("STOP;MODE,0") == ["OK", "IDLE", "OK"]
    assert omni4.cmd("MOVE,100,30,80,0") == ["OK"]  # near an idle axis: the weak pair stays on
    assert 0 < abs(omni4.hal.powers[1]) < 44


def test_the_floor_is_per_wheel() -> None:
    config = build_config(load_robot("omni4"))
    model = PowerModel(config, Calibration(config))
    out = [0] * 4
    model.floor = 42.0
    assert model.compute(0.2, 0.1, 0.0, False, out) & WEAK and out == [0, 82, 0, -82]
    model.floor = 0.0
    assert not model.compute(0.2, 0.1, 0.0, False, out) & WEAK and out == [41, 82, -41, -82]
