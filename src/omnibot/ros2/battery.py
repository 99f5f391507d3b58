"""The robot's battery on ROS 2: sensor_msgs/BatteryState of the voltage the controller reports against
the description's thresholds and chemistry (:func:`battery_state`), and its health in a word
(:func:`battery_health`) for ``/diagnostics``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from omnibot.logs import header, schemas
from omnibot.robot import RobotDescription, battery_level

# sensor_msgs/BatteryState constants
SUPPLY_STATUS_DISCHARGING = 2
SUPPLY_STATUS_NOT_CHARGING = 3
SUPPLY_HEALTH_UNKNOWN = 0
SUPPLY_HEALTH_GOOD = 1
SUPPLY_HEALTH_DEAD = 3
TECHNOLOGY = {"nimh": 1, "liion": 2, "lipo": 3, "life": 4}
BATTERY_MESSAGES = {
    "ok": "ok",
    "low": "low (below its warning threshold)",
    "limited": "very low: the controller limits the motors' power",
    "flat": "flat: the controller stopped the motors and holds them until charged",
}


def battery_health(robot: RobotDescription, voltage: float | None, stopped: bool = False) -> str:
    """``ok``, ``low``, ``limited``, ``flat`` or ``unknown``: the reading against the description's
    thresholds (robot/battery.py); ``stopped``: the controller holds its battery stop."""
    b = robot.battery
    return battery_level(voltage, b.warn_v, b.limit_v, b.stop_v, stopped)


def battery_state(robot: RobotDescription, voltage: float, ns: int, stopped: bool = False) -> Any:
    """sensor_msgs/BatteryState: the ``voltage`` the controller reports, the description's design
    capacity, chemistry and cell count; health GOOD above the stop threshold and DEAD below it or
    while the controller holds its battery stop (``stopped``), status DISCHARGING (the robot runs on
    it) or NOT_CHARGING once stopped; what the controller does not measure (current, charge,
    percentage, temperature) is NaN, as the message asks."""
    nan = math.nan
    level = battery_health(robot, voltage, stopped)
    health = {"unknown": SUPPLY_HEALTH_UNKNOWN, "flat": SUPPLY_HEALTH_DEAD}.get(level, SUPPLY_HEALTH_GOOD)
    return schemas.new(
        "sensor_msgs/msg/BatteryState",
        header=header(ns, "base_link"),
        voltage=float(voltage),
        temperature=nan,
        current=nan,
        charge=nan,
        capacity=nan,
        design_capacity=float(robot.battery.capacity_ah),
        percentage=nan,
        power_supply_status=SUPPLY_STATUS_NOT_CHARGING if level == "flat" else SUPPLY_STATUS_DISCHARGING,
        power_supply_health=health,
        power_supply_technology=TECHNOLOGY.get(robot.battery.chemistry, 0),
        present=True,
        cell_voltage=np.array([], dtype=np.float32),
        cell_temperature=np.array([], dtype=np.float32),
        location="",
        serial_number="",
    )
