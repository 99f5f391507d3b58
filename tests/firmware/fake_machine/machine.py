"""A fake MicroPython ``machine`` module for checking MachineHAL in CPython (recording, scriptable)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from tests.firmware.fake_mpu6050 import FakeI2C, FakeMPU6050

pins: dict[Any, Pin] = {}


class Clock:
    """Stands in for MicroPython's time module: ticks wrap at 2**30 like a board's."""

    PERIOD = 1 << 30

    def __init__(self) -> None:
        self.us = 0

    def ticks_us(self) -> int:
        return self.us % self.PERIOD

    def ticks_diff(self, a: int, b: int) -> int:
        half = self.PERIOD // 2
        return (a - b + half) % self.PERIOD - half

    def sleep_us(self, us: int) -> None:
        self.us += us


class Pin:
    IN = 0
    OUT = 1
    PULL_UP = 1
    IRQ_RISING = 1
    IRQ_FALLING = 2

    def __init__(self, id: Any, mode: int = -1, pull: int = -1, value: int | None = None) -> None:
        self.id = id
        self.mode = mode
        self._value = value or 0
        self.handler: Callable[[Pin], None] | None = None
        self.history: list[int] = []
        pins[id] = self

    def value(self, v: int | None = None) -> int:
        if v is None:
            return self._value
        self._value = v
        self.history.append(v)
        return v

    def irq(self, handler: Callable[[Pin], None], trigger: int) -> None:
        self.handler = handler

    def drive(self, v: int) -> None:
        """Test side: an external edge, with the interrupt handler run."""
        self._value = v
        if self.handler:
            self.handler(self)


class PWM:
    def __init__(self, pin: Pin) -> None:
        self.pin = pin
        self.duty = -1
        self.frequency = 0
        pin.pwm = self  # type: ignore[attr-defined]

    def freq(self, f: int) -> None:
        self.frequency = f

    def duty_u16(self, d: int) -> None:
        self.duty = d


class UART:
    def __init__(self, id: int, baudrate: int, tx: Pin, rx: Pin) -> None:
        self.id = id
        self.baudrate = baudrate
        self.rx = b""
        self.tx = b""

    def any(self) -> int:
        return len(self.rx)

    def read(self) -> bytes:
        data, self.rx = self.rx, b""
        return data

    def write(self, data: bytes) -> int:
        self.tx += data
        return len(data)


class ADC:
    def __init__(self, pin: Pin) -> None:
        self.raw = 0

    def read_u16(self) -> int:
        return self.raw


i2c_devices: dict[int, FakeMPU6050] = {}
"""The chips on every I2C bus the firmware opens (tests set them before building the HAL)."""


class I2C(FakeI2C):
    """An I2C bus with the register-level chips of ``i2c_devices`` on it."""

    def __init__(self, id: int, scl: Pin, sda: Pin, freq: int = 400000) -> None:
        super().__init__(i2c_devices)
        self.id, self.scl, self.sda, self.freq = id, scl, sda, freq
