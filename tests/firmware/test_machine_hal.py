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
from omnibot.protocol import codes
from omnibot.robot import load_robot
from tests.firmware.fake_mpu6050 import FakeMPU6050

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
        fake.i2c_devices.clear()
        fake.i2c_devices[0x68] = FakeMPU6050()
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
    adc.raw = 20000
    assert hal.battery_mv() == 10000
    machine.i2c_devices[0x68].rate_dps = -1.0  # -131 LSB at +-250 deg/s
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


def test_the_gyro_is_woken_and_set_up_from_the_pin_map(machine: Any) -> None:
    """The 3-entry form: bus 1, 0x68, 400 kHz, +-250 deg/s, DLPF 42 Hz; the chip's registers say so."""
    hal, _ = make(machine)
    chip = machine.i2c_devices[0x68]
    i2c: Any = hal._i2c
    assert (i2c.id, i2c.scl.id, i2c.sda.id, i2c.freq) == (1, 31, 30, 400000)
    assert not chip.asleep and chip.regs[0x6B] == 0x01  # awake on the X gyro's PLL
    assert (chip.regs[0x1A], chip.regs[0x1B], chip.regs[0x19]) == (3, 0, 0)
    assert hal.gyro_fault is None
    for dps, mdps in ((0.0, 0), (90.0, 90000), (-45.5, -45496), (300.0, 250129), (-300.0, -250137)):
        chip.rate_dps = dps  # beyond +-250 deg/s the chip saturates at its int16 limits
        assert hal.gyro_rate_mdps() == mdps


def test_a_gyro_at_0x69_with_another_range(machine: Any) -> None:
    machine.i2c_devices.clear()
    chip = machine.i2c_devices[0x69] = FakeMPU6050()
    pins = dict(PINS, gyro=[0, 5, 4, 0x69, 100000, 1, 6])  # +-500 deg/s, DLPF 5 Hz
    hal = MachineHAL(pins, 115200, 255, clock=machine.Clock())
    assert (chip.regs[0x1B], chip.regs[0x1A]) == (1 << 3, 6)
    chip.rate_dps = 400.0  # 26200 LSB at 65.5 LSB per deg/s
    assert hal.gyro_rate_mdps() == 400000


@pytest.mark.parametrize(
    ("devices", "fault"),
    [
        ({}, "no MPU6050 answers at 0x68"),  # nothing wired (or AD0 high: the chip is at 0x69)
        ({0x69: FakeMPU6050()}, "no MPU6050 answers at 0x68"),
        ({0x68: FakeMPU6050(who_am_i=0x70)}, "WHO_AM_I 0x70, not an MPU6050"),  # an MPU6500
        ({0x68: FakeMPU6050(takes_writes=False)}, "did not take its settings"),
    ],
)
def test_a_missing_gyro_is_reported_at_boot_and_the_firmware_runs_on(
    machine: Any, devices: dict[int, FakeMPU6050], fault: str
) -> None:
    machine.i2c_devices.clear()
    machine.i2c_devices.update(devices)
    hal, clock = make(machine)
    assert hal.gyro_fault is not None and fault in hal.gyro_fault
    assert hal.gyro_rate_mdps() is None
    config = build_config(load_robot("omni4"), pins=PINS)
    assert config["gyro"]  # the description has one
    ctrl = Controller(hal, config)
    uart: Any = hal._uart
    assert uart.tx == f"HELLO,2,omni4,4\r\nWARN,{codes.W_NO_GYRO},{codes.TEXTS[codes.W_NO_GYRO]}\r\n".encode()
    assert not ctrl.has_gyro
    uart.tx = b""
    uart.rx = b"TELEM,10,24\n"  # rate and heading: 0, the board has no gyro
    ctrl.poll()
    clock.us += 10000
    ctrl.poll()
    assert uart.tx.startswith(b"OK\r\nTEL,") and uart.tx.endswith(b",24,0,0\r\n")


def test_a_bus_failing_later_skips_the_samples(machine: Any) -> None:
    hal, _ = make(machine)
    machine.i2c_devices[0x68].rate_dps = 10.0
    assert hal.gyro_rate_mdps() == 10000  # 1310 LSB
    i2c: Any = hal._i2c
    i2c.fail = True
    assert hal.gyro_rate_mdps() is None
    i2c.fail = False
    assert hal.gyro_rate_mdps() == 10000
