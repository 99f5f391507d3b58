"""Host side (CPython): the board's pin map for ``MachineHAL`` (hal.py), an example for a Raspberry Pi Pico.

The gyro's I2C pins come from the robot description's MPU6050 wiring; every other pin is the
example's, to edit for a board's wiring (``pins`` of the config, docs/firmware.md).
"""

from __future__ import annotations

import math
from typing import Any

from omnibot.errors import ConfigError
from omnibot.firmware import mpu6050
from omnibot.robot import RobotDescription


def gyro_pins(robot: RobotDescription) -> list[int] | None:
    """The pin map's ``gyro`` entry (hal.py) from the description's MPU6050 wiring: ``[i2c_id, scl,
    sda, address, freq, fs_sel, dlpf_cfg]``; None without a gyro or for another model (no driver)."""
    g = robot.gyro
    if g is None or g.model.upper() != "MPU6050":
        return None
    range_dps = math.degrees(g.range)
    try:
        fs_sel = mpu6050.fs_sel_for(range_dps)
    except ValueError:
        raise ConfigError(
            f"{g.range} rad/s ({range_dps:.0f} deg/s) is beyond an MPU6050's 2000 deg/s",
            key="gyro.range",
        ) from None
    lsb = mpu6050.LSB_PER_DPS_X10[fs_sel] / 10.0  # counts per deg/s
    if g.resolution > 0 and abs(math.radians(1.0 / lsb) / g.resolution - 1.0) > 0.02:
        raise ConfigError(
            f"{g.resolution} rad/s per LSB does not match the MPU6050's "
            f"+-{mpu6050.FULL_SCALE_DPS[fs_sel]} deg/s range that gyro.range picks "
            f"({math.radians(1.0 / lsb):.4g} rad/s per LSB, {lsb:g} LSB per deg/s)",
            key="gyro.resolution",
        )
    return [
        g.i2c_bus,
        g.scl_pin,
        g.sda_pin,
        g.i2c_address,
        g.i2c_freq,
        fs_sel,
        mpu6050.dlpf_cfg_for(g.bandwidth_hz),
    ]


def default_pins(robot: RobotDescription) -> dict[str, Any]:
    """An example pin map for a Raspberry Pi Pico (RP2040); edit it for your wiring. The gyro's I2C
    pins come from the description; where they take the UART's (GP0, GP1: the defaults do), the
    protocol runs on USB (``"uart": None``). A pin used twice is a ConfigError naming the gyro's key."""
    n = robot.n_wheels
    gyro = gyro_pins(robot)
    uart: list[int] | None = [0, 0, 1]
    if gyro is not None and {gyro[1], gyro[2]} & {0, 1}:
        uart = None
    pins: dict[str, Any] = {
        "uart": uart,
        "pwm_freq": 1000,
        "motors": [[2 + 3 * i, 3 + 3 * i, 4 + 3 * i] for i in range(n)],
        "encoders": [[14 + 2 * i, 15 + 2 * i] for i in range(n)] if robot.encoders.motors else [],
        "tracking": [],
        "sonars": [[22, 26]][: len(robot.sonars)],
        "battery": [28, round(3300.0 * 3 / 65535, 6)],
        "gyro": gyro,
    }
    if gyro is not None:
        used = _pins_used(pins, but="gyro")
        for key, pin in (("gyro.scl_pin", gyro[1]), ("gyro.sda_pin", gyro[2])):
            if pin in used:
                raise ConfigError(
                    f"pin {pin} is the board's {used[pin]} pin already (free pins: "
                    f"{', '.join(str(p) for p in range(29) if p not in used and p not in (23, 24, 25))})",
                    key=key,
                )
        if gyro[1] == gyro[2]:
            raise ConfigError(f"SCL and SDA are both pin {gyro[1]}", key="gyro.scl_pin")
    return pins


def _pins_used(pins: dict[str, Any], but: str) -> dict[int, str]:
    """Every pin of the map (its key) except those of ``but``."""
    used: dict[int, str] = {}
    uart = pins["uart"]
    if uart:
        used.update({uart[1]: "uart", uart[2]: "uart"})
    for key in ("motors", "encoders", "tracking", "sonars"):
        if key != but:
            used.update({p: key for group in pins[key] for p in group if p >= 0})
    if pins["battery"] and but != "battery":
        used[pins["battery"][0]] = "battery"
    return used
