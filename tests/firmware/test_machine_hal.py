"""MachineHAL against a fake ``machine`` module (tests/firmware/fake_machine on sys.path)."""

from __future__ import annotations

import importlib
import sys
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

from omnibot.firmware.config import build_config
from omnibot.firmware.controller import Controller
from omnibot.firmware.hal import MachineHAL
from omnibot.robot.description import load_robot

FAKE = str(Path(__file__).with_name("fake_machine"))

PINS = {
    "uart": [0, 0, 1],
    "pwm_freq": 2000,
    "motors": [[2, 3, 4], [5, 6, 7], [8, 9, -1], [11, 12, 13]],
    "encoders": [[14, 15], [16, 17], [18, 19], [20, 21]],
    "tracking": [[26, 27]],
    "sonars": [[22, 28]],
    "battery": [29, 0.5],
    "gyro": [1, 31, 30],
}


@pytest.fixture
def machine() -> Iterator[ModuleType]:
    sys.path.insert(0, FAKE)
    sys.modules.pop("machine", None)
    try:
        fake: Any = importlib.import_module("machine")
        fake.pins.clear()
        yield fake
    finally:
        sys.path.remove(FAKE)
        sys.modules.pop("machine", None)


def make(machine: Any) -> tuple[MachineHAL, Any]:
    clock = machine.Clock()
    return MachineHAL(PINS, 115200, 255, clock=clock), clock


def test_motor_power_sets_direction_and_duty(machine: Any) -> None:
    hal, _ = make(machine)
    pins = machine.pins
    assert pins[2].pwm.frequency == 2000
    hal.set_power(0, 255)
    assert (pins[3].value(), pins[4].value(), pins[2].pwm.duty) == (1, 0, 65535)
    hal.set_power(0, -51)
    assert (pins[3].value(), pins[4].value(), pins[2].pwm.duty) == (0, 1, 13107)
    hal.set_power(0, 0)
    assert (pins[3].value(), pins[4].value(), pins[2].pwm.duty) == (0, 0, 0)
    hal.set_power(2, -100)  # single direction pin
    assert pins[9].value() == 0 and pins[8].pwm.duty == 100 * 65535 // 255


def test_quadrature_counts_both_directions(machine: Any) -> None:
    hal, _ = make(machine)
    a, b = machine.pins[14], machine.pins[15]
    for _ in range(5):  # A leads B: forward
        a.drive(1)
        b.drive(1)
        a.drive(0)
        b.drive(0)
    assert hal.encoder_count(0) == 10
    for _ in range(3):  # B leads A: backward
        b.drive(1)
        a.drive(1)
        b.drive(0)
        a.drive(0)
    assert hal.encoder_count(0) == 4
    machine.pins[26].drive(1)
    assert hal.tracking_count(0) == 1
    assert hal.encoder_count(3) == 0


def test_sonar_echo_timing_is_non_blocking(machine: Any) -> None:
    hal, clock = make(machine)
    trig, echo = machine.pins[22], machine.pins[28]
    assert hal.sonar_read(0) == -1  # never started
    hal.sonar_start(0)
    assert trig.history == [1, 0]  # the 10 us trigger pulse
    assert hal.sonar_read(0) is None
    clock.us += 500
    echo.drive(1)
    assert hal.sonar_read(0) is None
    clock.us += 58 * 123
    echo.drive(0)
    assert hal.sonar_read(0) == 123
    assert hal.sonar_read(0) == -1
    hal.sonar_start(0)
    clock.us += 31000  # no echo
    assert hal.sonar_read(0) == -1


def test_uart_battery_gyro_ticks(machine: Any) -> None:
    hal, clock = make(machine)
    uart: Any = hal._uart
    uart.rx = b"HELLO\n"
    assert hal.uart_read() == b"HELLO\n"
    assert hal.uart_read() == b""
    hal.uart_write(b"OK\r\n")
    assert uart.tx == b"OK\r\n"
    adc: Any = hal._adc
    i2c: Any = hal._i2c
    adc.raw = 20000
    assert hal.battery_mv() == 10000
    assert i2c.writes == [(0x68, 0x6B, b"\x00")]
    i2c.mem[(0x68, 0x47)] = bytes([0xFF, 0x7D])  # -131 LSB = -1 deg/s
    assert hal.gyro_rate_mdps() == -1000
    clock.us = (1 << 30) - 10
    t0 = hal.ticks_us()
    clock.us += 30
    assert hal.ticks_diff(hal.ticks_us(), t0) == 30  # across the wrap


def test_controller_runs_on_machine_hal_across_tick_wrap(machine: Any) -> None:
    hal, clock = make(machine)
    clock.us = (1 << 30) - 20000  # the tick counter wraps 20 ms into the run
    ctrl = Controller(hal, build_config(load_robot("omni4"), pins=PINS))
    uart: Any = hal._uart
    assert uart.tx == b"HELLO,2,omni4,4\r\n"
    uart.rx = b"ROTATE,90,90\n"
    ctrl.poll()
    assert machine.pins[2].pwm.duty > 0
    for _ in range(1000):
        clock.us += 1000
        ctrl.poll()
    assert machine.pins[2].pwm.duty == 0
    assert uart.tx.endswith(b"OK\r\nIDLE\r\n")
    assert ctrl.now_ms == 1000
