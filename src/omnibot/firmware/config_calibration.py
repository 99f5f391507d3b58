"""Host side (CPython): the config's calibration keys (``k`` ... ``reach``) from a robot description.

The description's calibration as the firmware's tables, neutral ones without it; calibration K is
the motors' nominal one when the description gives none.
"""

from __future__ import annotations

from typing import Any

from omnibot.errors import ConfigError
from omnibot.robot import PiecewiseLinear, RobotDescription


def _table(t: PiecewiseLinear | None) -> list[list[float]]:
    if t is None:
        return [[0.0], [1.0]]
    return [[float(x) for x in t.x], [float(y) for y in t.y]]


def _default_k(robot: RobotDescription) -> float:
    """PWM counts per m/s of rim speed from the motor model, when the description gives no K."""
    w = robot.wheels[0]
    m = w.motor
    volts = max(robot.battery.voltage - m.driver_drop, 0.1)
    v_free = volts / (m.torque_constant * m.gear_ratio) * w.radius
    return m.pwm_max / v_free


def calibration_keys(robot: RobotDescription) -> dict[str, Any]:
    """k ... reach: the description's calibration as tables (neutral ones without it)."""
    cal = robot.calibration
    n = robot.n_wheels
    if cal and cal.k_l:
        courses = [float(c) for c in cal.k_l.courses_deg]
        kl_tables = [_table(c) for c in cal.k_l.curves]
    else:
        courses, kl_tables = [0.0], [_table(None)]
    motors = cal.motors if cal else None
    if motors is not None and len(motors.offset) != n:
        raise ConfigError(f"{len(motors.offset)} motors for a robot with {n}", key="calibration.motors")
    rollers = cal.rollers if cal else None
    if rollers is not None and len(rollers.cos) != n:
        raise ConfigError(
            f"roller drag for {len(rollers.cos)} wheels on a robot with {n}",
            key="calibration.rollers",
        )
    return {
        "k": calibration_k(robot),
        "kl_courses": courses,
        "kl_tables": kl_tables,
        "kt": _table(cal.k_t if cal else None),
        "kr": _table(cal.k_r if cal else None),
        "motor_offset": [float(o) for o in motors.offset] if motors else [0.0] * n,
        "motor_gain": [_table(g) for g in motors.gain] if motors else [_table(None)] * n,
        "motor_speed": list(motors.speed) if motors and motors.speed else [0.0] * n,
        "roller_cos": list(rollers.cos) if rollers else [0.0] * n,
        "roller_sin": list(rollers.sin) if rollers else [0.0] * n,
        "roller_coast": (
            [[round(100.0 * x, 6) for x in rollers.coast.x], list(rollers.coast.y)]
            if rollers and rollers.coast
            else [[0.0], [0.0]]
        ),
        "reach": (
            [list(cal.reach.courses_deg), [round(100.0 * v, 6) for v in cal.reach.speed]]
            if cal and cal.reach
            else [[0.0], [0.0]]
        ),
    }


def calibration_k(robot: RobotDescription) -> float:
    """Calibration K: the description's, else the motors' nominal one."""
    return float(robot.calibration.k) if robot.calibration else _default_k(robot)
